/* Prints the first 4096 points of GSL's niederreiter_2 in dimension 12
 * (coordinate j of the dimension-12 generator equals that of any dimension >= j)
 * as raw 31-bit integers (GSL returns integer * 2^-31 exactly), hex, one point
 * per line, in GSL's output (Gray-code) order. */
#include <stdio.h>
#include <gsl/gsl_qrng.h>
#include <gsl/gsl_version.h>
int main(void) {
  const unsigned d = 12;
  gsl_qrng *q = gsl_qrng_alloc(gsl_qrng_niederreiter_2, d);
  double v[12];
  printf("# GSL %s gsl_qrng_niederreiter_2, dims 1..12, 4096 points, value*2^31 in hex, GSL (Gray-code) order\n", GSL_VERSION);
  for (int k = 0; k < 4096; k++) {
    gsl_qrng_get(q, v);
    for (unsigned j = 0; j < d; j++) {
      double s = v[j] * 2147483648.0; /* exact: v = int * 2^-31 */
      unsigned long x = (unsigned long)s;
      if ((double)x != s) { fprintf(stderr, "inexact\n"); return 1; }
      printf(j ? " %08lx" : "%08lx", x);
    }
    printf("\n");
  }
  gsl_qrng_free(q);
  return 0;
}
