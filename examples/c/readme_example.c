/* The README's C example: Lécot et al.'s coagulation-fragmentation test with the
 * mass-flow scheme, stepped by a host loop and compared with the exact moment. */
#include <coagula.h>
#include <stdio.h>
#include <stdlib.h>

static void die(int status) {
    char msg[256];
    coag_last_error_message(msg, sizeof msg, NULL);
    fprintf(stderr, "%s: %s\n", coag_status_name(status), msg);
    exit(1);
}
#define TRY(call) do { int s_ = (call); if (s_ != COAG_OK) die(s_); } while (0)

int main(void) {
    coag_kernel *k;
    coag_fragmentation *f;
    TRY(coag_kernel_new("constant", (const double[]){1.0}, 1, &k)); /* K(x, y) = 1 */
    TRY(coag_fragmentation_new_binary_uniform(1.0, &f));   /* F(x, y) = 2/(x + y) */

    coag_options *opts;                                    /* every option at its default: */
    TRY(coag_options_new(&opts));                          /* QMC points, seed 0 */
    TRY(coag_options_set_real(opts, "dt", 0.01));          /* the time step */
    enum { N = 1 << 14 };
    static double sizes[N];
    for (int i = 0; i < N; i++) sizes[i] = 1.0;            /* c(x, 0) = delta(x - 1) */

    coag_sim *sim;                                         /* scheme "massflow", mass M1 = 1 */
    TRY(coag_sim_new_sizes("massflow", k, f, opts, sizes, N, 1.0, &sim));
    coag_kernel_free(k);                                   /* the sim keeps a copy */
    coag_fragmentation_free(f);
    coag_options_free(opts);

    for (int step = 1; step <= 10; step++) {               /* the host's outer steps */
        double t = 0.1 * step, m2, exact;
        coag_step_report rep;
        coag_step_report_init(&rep, sizeof rep); /* sets rep.struct_size (the ABI's growth rule) */
        TRY(coag_sim_advance_to(sim, t, &rep));
        TRY(coag_sim_moment(sim, 2.0, &m2));
        TRY(coag_exact_moment(COAG_EXACT_COAG_FRAG, 2, t, &exact));
        printf("t = %.1f  M2 = %.6f  exact %.6f  (%llu events, %llu clipped)\n", t, m2, exact,
               (unsigned long long)rep.events, (unsigned long long)rep.clipped);
    }
    coag_sim_free(sim);
    return 0;
}
