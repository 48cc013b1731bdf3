/* Issue 40's calls that never returned on accepted input: under a host work limit each
 * returns (COAG_INTERRUPTED, or a refusal), the sim still valid; a lone particle of size
 * 1e-300, a fragmentation rate of 1e300 and a period-2 random callback included.
 * Built with sanitizers and run under valgrind in CI (COAG_TEST_QUICK: smaller limits). */
#include <stdint.h>
#include <string.h>

#include "check.h"

static uint64_t limit;
static int period;
static uint64_t period2(void *ud) {
    (void)ud;
    return (period++ & 1) ? 0x9e3779b97f4a7c15ULL : 0x0123456789abcdefULL;
}

static double rate1(double x, void *ud) {
    (void)x;
    (void)ud;
    return 1.0;
}
static double rate5(double x, void *ud) {
    (void)x;
    (void)ud;
    return 5.0;
}
static double twice(double x, double u, void *ud) {
    (void)u;
    (void)ud;
    return 2.0 * x;
}
static double half(double x, double u, void *ud) {
    (void)u;
    (void)ud;
    return 0.5 * x;
}
static double infinite(const double *x, const double *u, size_t dim, void *ud) {
    (void)x;
    (void)u;
    (void)dim;
    (void)ud;
    return INFINITY;
}

/* Wrong or silent statuses of the review: a fragment larger than its particle, a
 * fragmentation rate above its declared supremum, a Langevin mean of one trajectory
 * or of an infinite observable. */
static void statuses(const coag_kernel *k1, const double *ones) {
    coag_options *o = NULL;
    OK(coag_options_new(&o));
    OK(coag_options_set_real(o, "dt", 0.01));
    coag_user_fragmentation uf;
    memset(&uf, 0, sizeof uf);
    uf.rate = rate1;
    uf.inverse_piece = twice;
    uf.sup_rate = 1.0;
    coag_fragmentation *big = NULL, *fast = NULL;
    OK(coag_fragmentation_new_user(&uf, &big));
    uf.rate = rate5;
    uf.inverse_piece = half;
    OK(coag_fragmentation_new_user(&uf, &fast));
    const char *breaking[3] = {"massflow", "mfa", "dsa"};
    for (int i = 0; i < 3; i++) {
        const coag_fragmentation *fr[2] = {big, fast};
        for (int j = 0; j < 2; j++) {
            coag_sim *s = NULL;
            int st = coag_sim_new_sizes(breaking[i], k1, fr[j], i == 0 ? o : NULL, ones, 8, 1.0, &s);
            if (st == COAG_OK) st = coag_sim_advance_to(s, 1.0, NULL);
            CHECK(st == COAG_INVALID_RATE, "%s, %s: %s", breaking[i], j ? "rate above sup" : "piece > x",
                  coag_status_name(st));
            coag_sim_free(s);
        }
    }
    coag_fragmentation_free(big);
    coag_fragmentation_free(fast);
    coag_options_free(o);
    coag_langevin_config c;
    OK(coag_langevin_default_config(&c, sizeof c));
    coag_langevin *one = NULL, *two = NULL;
    double x0[2] = {0.5, 0.25}, u0[2] = {0.0, 0.0}, m = -1.0, se = -1.0;
    OK(coag_langevin_new(&c, 1, x0, u0, 1, 0, &one));
    OK(coag_langevin_new(&c, 2, x0, u0, 1, 0, &two));
    OK(coag_langevin_advance_to(one, 0.1, NULL));
    OK(coag_langevin_advance_to(two, 0.1, NULL));
    EXPECT(coag_langevin_mean(one, NULL, NULL, &m, &se, NULL), COAG_INVALID_ARGUMENT);
    CHECK(m == -1.0 && se == -1.0, "nothing written");
    EXPECT(coag_langevin_mean(two, infinite, NULL, &m, &se, NULL), COAG_INVALID_RATE);
    OK(coag_langevin_mean(two, NULL, NULL, &m, &se, NULL));
    CHECK(isfinite(m) && isfinite(se), "two trajectories: %g ± %g", m, se);
    coag_langevin_free(one);
    coag_langevin_free(two);
}

static coag_kernel *kernel(const char *name, const double *p, size_t n) {
    coag_kernel *k = NULL;
    OK(coag_kernel_new(name, p, n, &k));
    return k;
}

/* The sim returns from advance_to(t): interrupted or refused, never OK past its work. */
static void returns(coag_sim *s, double t, const char *what) {
    OK(coag_sim_set_work_limit(s, limit));
    int st = coag_sim_advance_to(s, t, NULL);
    double now = -1.0;
    OK(coag_sim_time(s, &now));
    CHECK(st == COAG_INTERRUPTED || st == COAG_CAPACITY || st == COAG_INVALID_ARGUMENT || st == COAG_OK,
          "%s: %s", what, coag_status_name(st));
    CHECK(st != COAG_OK || now == t, "%s: OK at t = %g", what, now);
    coag_sim_free(s);
}

int main(void) {
    limit = test_quick() ? 50000 : 5000000;
    coag_kernel *k1 = kernel("constant", (const double[]){1.0}, 1);
    coag_kernel *kxy = kernel("multiplicative", (const double[]){1.0}, 1);
    coag_kernel *kbr = kernel("brownian", (const double[]){1.0}, 1);
    coag_kernel *kh = kernel("homogeneous", (const double[]){1.5, 1.0}, 2);
    double ones[64];
    for (int i = 0; i < 64; i++) ones[i] = 1.0;
    coag_sim *s = NULL;
    coag_options *o = NULL;

    /* mass flow to 1e300, and after set_dt(5e-324) */
    OK(coag_options_new(&o));
    OK(coag_options_set_real(o, "dt", 0.01));
    OK(coag_sim_new_sizes("massflow", k1, NULL, o, ones, 64, 1.0, &s));
    returns(s, 1e300, "massflow to 1e300");
    OK(coag_sim_new_sizes("massflow", k1, NULL, o, ones, 64, 1.0, &s));
    int st = coag_sim_set_dt(s, 5e-324);
    CHECK(st == COAG_OK || st == COAG_INVALID_ARGUMENT, "set_dt(5e-324): %s", coag_status_name(st));
    returns(s, 1.0, "massflow dt 5e-324");
    coag_options_free(o);

    /* K = xy from 10^4 monomers to 1e300: doubling after the gel */
    const char *gelling[3] = {"lowrank", "rejection", "lowrank-tree"};
    uint64_t n4[1] = {10000};
    for (int i = 0; i < 3; i++) {
        OK(coag_sim_new_counts(gelling[i], kxy, NULL, NULL, n4, 1, 10000.0, &s));
        returns(s, 1e300, gelling[i]);
    }
    /* {0, 2^40} in V = 1: ~6e14 events to 1e-9 */
    const char *counted[3] = {"inverse", "lowrank-tree", "dsa-counts"};
    uint64_t big[2] = {0, 1ULL << 40}, n100[1] = {100};
    for (int i = 0; i < 3; i++) {
        OK(coag_sim_new_counts(counted[i], k1, NULL, NULL, n100, 1, 1.0, &s));
        OK(coag_sim_set_counts(s, big, 2, 1.0));
        returns(s, 1e-9, counted[i]);
    }
    /* MFA: binary uniform at rate 1e300; homogeneous(1.5) without truncation; a
     * period-2 host stream */
    coag_fragmentation *fr = NULL;
    OK(coag_fragmentation_new_binary_uniform(1e300, &fr));
    OK(coag_sim_new_sizes("mfa", k1, fr, NULL, ones, 64, 1.0, &s));
    returns(s, 1.0, "mfa fragmentation 1e300");
    coag_fragmentation_free(fr);
    OK(coag_sim_new_sizes("mfa", kh, NULL, NULL, ones, 44, 1.0, &s));
    returns(s, 10.0, "mfa homogeneous(1.5)");
    OK(coag_sim_new_sizes("mfa", k1, NULL, NULL, ones, 64, 1.0, &s));
    OK(coag_sim_set_rng_callback(s, period2, NULL));
    returns(s, 10.0, "mfa period-2 stream");
    /* DSA, Brownian kernel, a particle of size 1e-300 */
    double tiny[2] = {1e-300, 1.0};
    OK(coag_sim_new_sizes("dsa", kbr, NULL, NULL, tiny, 2, 1.0, &s));
    returns(s, 1.0, "dsa 1e-300");
    /* a temperature model from 2^63 particles, a gas to 1e300 */
    coag_kernel *kt = kernel("temperature-closed-form", (const double[]){1.0, 0.5}, 2);
    coag_kernel *kg = kernel("hard-spheres", (const double[]){0.9}, 1);
    uint64_t huge[1] = {1ULL << 63}, n1000[1] = {1000};
    double temp[1] = {1.0};
    OK(coag_sim_new_temperatures("temperature", kt, NULL, huge, temp, 1, 1.0, &s));
    returns(s, 1.0, "temperature 2^63");
    OK(coag_sim_new_maxwellian("dsmc", kg, NULL, n1000, temp, 1, 10000.0, &s));
    returns(s, 1e300, "dsmc to 1e300");

    statuses(k1, ones);
    coag_kernel_free(k1);
    coag_kernel_free(kxy);
    coag_kernel_free(kbr);
    coag_kernel_free(kh);
    coag_kernel_free(kt);
    coag_kernel_free(kg);
    return finish("test_review");
}
