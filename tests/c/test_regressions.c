/* Issue 12's defects as a C process simulator met them: a kernel that turns NaN
 * mid-run must not lose mass (inverse method), a kernel above its declared bound is an
 * error rather than a silently capped rate, and a checkpoint taken before the size table
 * grew restores into a grown sim and continues (no COAG_PANIC). */
#include <stdint.h>
#include <string.h>

#include "check.h"

static double nan_beyond_4(double x, double y, void *ud) {
    (void)ud;
    return (x + y > 4.0) ? NAN : 1.0;
}

/* K = 2 x y with factors a = x/2, b = x: the declared bound is x y, half the kernel. */
static double twice_product(double x, double y, void *ud) {
    (void)ud;
    return 2.0 * x * y;
}
static void half_product_factors(double x, double *a, double *b, void *ud) {
    (void)ud;
    a[0] = 0.5 * x;
    b[0] = x;
}

/* Sum of i * N_i over the sim's counts. */
static uint64_t mass_of(coag_sim *s) {
    size_t len;
    OK(coag_sim_state_len(s, &len));
    uint64_t *c = calloc(len, sizeof *c);
    double v;
    OK(coag_sim_get_counts(s, c, len, &v));
    uint64_t m = 0;
    for (size_t i = 0; i < len; i++) m += (uint64_t)(i + 1) * c[i];
    free(c);
    return m;
}

int main(void) {
    /* item 8: the inverse method, NaN for x + y > 4 */
    coag_user_kernel desc = {nan_beyond_4, NULL, 0, NULL, 0, NULL, NULL};
    coag_kernel *nk;
    OK(coag_kernel_new_user(&desc, &nk));
    coag_counts_config c;
    OK(coag_counts_default_config(&c, sizeof c));
    c.method = COAG_METHOD_INVERSE;
    uint64_t counts[1] = {1000};
    coag_sim *s;
    OK(coag_counts_new(&c, nk, counts, 1, &s));
    int st = COAG_OK;
    double t = 0.0;
    while (st == COAG_OK && t < 100.0) {
        t += 0.01;
        st = coag_sim_advance_to(s, t, NULL);
    }
    CHECK(st == COAG_INVALID_RATE, "NaN reported: %s", coag_status_name(st));
    uint64_t m = mass_of(s);
    CHECK(m % 1000 == 0 && ((m / 1000) & (m / 1000 - 1)) == 0, "mass %llu conserved up to doubling",
          (unsigned long long)m);
    coag_sim_free(s);
    coag_kernel_free(nk);

    /* item 9: a kernel above its declared low-rank bound */
    coag_user_kernel over = {twice_product, NULL, 1, half_product_factors, 0, NULL, NULL};
    coag_kernel *ok;
    OK(coag_kernel_new_user(&over, &ok));
    OK(coag_counts_default_config(&c, sizeof c));
    OK(coag_counts_new(&c, ok, counts, 1, &s));
    EXPECT(coag_sim_advance_to(s, 0.3, NULL), COAG_INVALID_RATE);
    double tm = -1.0;
    OK(coag_sim_time(s, &tm));
    CHECK(tm == 0.0, "time unchanged: %g", tm);
    uint64_t n = 0;
    OK(coag_sim_particle_count(s, &n));
    CHECK(n == 1000, "no event applied: %llu particles", (unsigned long long)n);
    coag_sim_free(s);
    coag_kernel_free(ok);

    /* item 7: restore a small-M checkpoint into the grown sim, then grow again */
    coag_kernel *add;
    OK(coag_kernel_new_additive(1.0, &add));
    OK(coag_counts_default_config(&c, sizeof c));
    uint64_t mono[1] = {2000};
    OK(coag_counts_new(&c, add, mono, 1, &s));
    OK(coag_sim_advance_to(s, 0.1, NULL));
    size_t need;
    OK(coag_sim_checkpoint_size(s, &need));
    uint8_t *buf = malloc(need);
    size_t written;
    OK(coag_sim_checkpoint(s, buf, need, &written));
    OK(coag_sim_advance_to(s, 3.0, NULL));
    uint64_t grown_mass = mass_of(s);
    OK(coag_sim_restore(s, buf, written));
    OK(coag_sim_advance_to(s, 3.0, NULL)); /* used to be COAG_PANIC */
    CHECK(mass_of(s) == grown_mass, "the same run again: mass %llu vs %llu",
          (unsigned long long)mass_of(s), (unsigned long long)grown_mass);
    free(buf);
    coag_sim_free(s);
    coag_kernel_free(add);

    return finish("test_regressions");
}
