/* Misuse of the C ABI: NULL handles and outputs, zero lengths, too-small buffers, NaN
 * parameters, wrong scheme, bad checkpoints, and use after a failed call. Every call
 * must return an error code (never crash), leave outputs untouched and the handle
 * usable. Built with -fsanitize=address,undefined. */
#include <stdint.h>
#include <string.h>

#include "check.h"

static double nan_kernel(double x, double y, void *ud) {
    (void)ud;
    return (x + y > 4.0) ? NAN : 1.0;
}

int main(void) {
    coag_kernel *k = NULL;
    coag_fragmentation *f = NULL;
    coag_sim *s = NULL;
    double d = -7.0;
    uint64_t u = 77;
    size_t z = 77;

    /* constructors: NULL outs, NaN and out-of-range parameters */
    EXPECT(coag_kernel_new_constant(1.0, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_kernel_new_constant(NAN, &k), COAG_INVALID_ARGUMENT);
    EXPECT(coag_kernel_new_constant(-1.0, &k), COAG_INVALID_ARGUMENT);
    EXPECT(coag_kernel_new_product(1.5, &k), COAG_INVALID_ARGUMENT);
    EXPECT(coag_kernel_new_homogeneous(0.5, &k), COAG_INVALID_ARGUMENT);
    EXPECT(coag_kernel_new_additive(-1.0, &k), COAG_INVALID_ARGUMENT);
    CHECK(k == NULL, "no handle written on error");
    EXPECT(coag_fragmentation_new_binary_uniform(0.0, &f), COAG_INVALID_ARGUMENT);
    EXPECT(coag_kernel_new_user(NULL, &k), COAG_NULL_PARAMETER);
    coag_user_kernel bad = {NULL, NULL, 0, NULL, 0, NULL, NULL};
    EXPECT(coag_kernel_new_user(&bad, &k), COAG_INVALID_ARGUMENT);
    bad.rate = nan_kernel;
    bad.rank = 9;
    EXPECT(coag_kernel_new_user(&bad, &k), COAG_INVALID_ARGUMENT);
    bad.rank = 1; /* rank without factors */
    EXPECT(coag_kernel_new_user(&bad, &k), COAG_INVALID_ARGUMENT);
    coag_user_fragmentation badf = {NULL, NULL, -1.0, NULL};
    EXPECT(coag_fragmentation_new_user(&badf, &f), COAG_INVALID_ARGUMENT);

    /* the last error message, with a too-small buffer and a length query */
    char small[4];
    size_t len = 0;
    EXPECT(coag_last_error_message(small, sizeof small, &len), COAG_BUFFER_TOO_SMALL);
    CHECK(len > 4 && small[3] == '\0', "truncated and terminated");
    EXPECT(coag_last_error_message(NULL, 0, &len), COAG_OK);
    EXPECT(coag_last_error_message(NULL, 5, &len), COAG_NULL_PARAMETER);
    EXPECT(coag_last_error_message(small, 0, &len), COAG_BUFFER_TOO_SMALL);
    CHECK(strcmp(coag_status_name(12345), "COAG_UNKNOWN") == 0, "unknown status name");

    OK(coag_kernel_new_constant(1.0, &k));
    EXPECT(coag_kernel_rate(k, 1.0, 2.0, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_kernel_rate(NULL, 1.0, 2.0, &d), COAG_NULL_PARAMETER);

    /* sim constructors */
    coag_massflow_config mc;
    OK(coag_massflow_default_config(&mc, sizeof mc));
    double sizes[6] = {1, 1, 1, 1, 1, 1};
    EXPECT(coag_massflow_new(NULL, k, NULL, sizes, 4, &s), COAG_NULL_PARAMETER);
    EXPECT(coag_massflow_new(&mc, NULL, NULL, sizes, 4, &s), COAG_NULL_PARAMETER);
    EXPECT(coag_massflow_new(&mc, k, NULL, NULL, 4, &s), COAG_NULL_PARAMETER);
    EXPECT(coag_massflow_new(&mc, k, NULL, sizes, 0, &s), COAG_INVALID_ARGUMENT);
    EXPECT(coag_massflow_new(&mc, k, NULL, sizes, 6, &s), COAG_INVALID_ARGUMENT); /* not 2^m */
    mc.dt = NAN;
    EXPECT(coag_massflow_new(&mc, k, NULL, sizes, 4, &s), COAG_INVALID_ARGUMENT);
    mc.dt = 0.01;
    mc.points = 17;
    EXPECT(coag_massflow_new(&mc, k, NULL, sizes, 4, &s), COAG_INVALID_ARGUMENT);
    mc.points = COAG_POINTS_MONTE_CARLO;
    mc.randomization = COAG_RANDOMIZATION_OWEN;
    EXPECT(coag_massflow_new(&mc, k, NULL, sizes, 4, &s), COAG_INVALID_ARGUMENT);
    sizes[2] = -1.0;
    OK(coag_massflow_default_config(&mc, sizeof mc));
    EXPECT(coag_massflow_new(&mc, k, NULL, sizes, 4, &s), COAG_INVALID_ARGUMENT);
    CHECK(s == NULL, "no sim written on error");

    coag_eventflow_config ec;
    EXPECT(coag_eventflow_default_config(NULL, sizeof ec), COAG_NULL_PARAMETER);
    EXPECT(coag_eventflow_default_config(&ec, 8), COAG_INVALID_ARGUMENT);
    OK(coag_eventflow_default_config(&ec, sizeof ec));
    sizes[2] = 1.0;
    EXPECT(coag_eventflow_new(NULL, k, NULL, sizes, 4, &s), COAG_NULL_PARAMETER);
    EXPECT(coag_eventflow_new(&ec, NULL, NULL, sizes, 4, &s), COAG_NULL_PARAMETER);
    EXPECT(coag_eventflow_new(&ec, k, NULL, NULL, 4, &s), COAG_NULL_PARAMETER);
    EXPECT(coag_eventflow_new(&ec, k, NULL, sizes, 4, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_eventflow_new(&ec, k, NULL, sizes, 0, &s), COAG_INVALID_ARGUMENT);
    ec.struct_size = 4; /* not a config this library knows */
    EXPECT(coag_eventflow_new(&ec, k, NULL, sizes, 4, &s), COAG_INVALID_ARGUMENT);
    CHECK(s == NULL, "no sim written on error");
    OK(coag_eventflow_default_config(&ec, sizeof ec));
    OK(coag_eventflow_new(&ec, k, NULL, sizes, 4, &s));
    EXPECT(coag_sim_eventflow_config(s, NULL, sizeof ec), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_eventflow_config(NULL, &ec, sizeof ec), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_eventflow_config(s, &ec, 8), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_dt(s, 0.1), COAG_UNSUPPORTED);
    size_t ewb;
    EXPECT(coag_eventflow_workspace_size(NULL, NULL, 4, &ewb), COAG_NULL_PARAMETER);
    EXPECT(coag_eventflow_workspace_size(&ec, NULL, 4, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_eventflow_workspace_size(&ec, NULL, SIZE_MAX, &ewb), COAG_CAPACITY);
    OK(coag_eventflow_workspace_size(&ec, NULL, 4, &ewb));
    coag_sim *es = NULL;
    EXPECT(coag_eventflow_new_in(&ec, k, NULL, sizes, 4, NULL, ewb, &es), COAG_NULL_PARAMETER);
    EXPECT(coag_eventflow_new_in(NULL, k, NULL, sizes, 4, sizes, ewb, &es), COAG_NULL_PARAMETER);
    CHECK(es == NULL, "no sim written on error");
    coag_massflow_config mback;
    EXPECT(coag_sim_massflow_config(s, &mback, sizeof mback), COAG_UNSUPPORTED);
    coag_sim_free(s);
    s = NULL;

    coag_counts_config lc;
    OK(coag_counts_default_config(&lc, sizeof lc));
    uint64_t counts[2] = {0, 0};
    /* no particles: a valid, empty system (issue 14) */
    OK(coag_counts_new(&lc, k, counts, 2, &s));
    coag_sim_free(s);
    OK(coag_counts_new(&lc, k, counts, 0, &s));
    coag_sim_free(s);
    s = NULL;
    lc.method = 42;
    counts[0] = 100;
    EXPECT(coag_counts_new(&lc, k, counts, 2, &s), COAG_INVALID_ARGUMENT);
    lc.method = COAG_METHOD_REJECTION;
    bad.rank = 0; /* a user kernel without sup cannot do acceptance-rejection */
    coag_kernel *nk;
    OK(coag_kernel_new_user(&bad, &nk));
    EXPECT(coag_counts_new(&lc, nk, counts, 2, &s), COAG_UNSUPPORTED);
    lc.method = COAG_METHOD_LOWRANK; /* ... nor low-rank MC without factors */
    EXPECT(coag_counts_new(&lc, nk, counts, 2, &s), COAG_UNSUPPORTED);
    lc.volume = NAN;
    EXPECT(coag_counts_new(&lc, k, counts, 2, &s), COAG_INVALID_ARGUMENT);
    /* configs carry their size: a zeroed or a larger-than-ours struct is refused */
    OK(coag_counts_default_config(&lc, sizeof lc));
    CHECK(lc.struct_size == sizeof lc, "default config sets struct_size: %zu", lc.struct_size);
    lc.struct_size = 0;
    EXPECT(coag_counts_new(&lc, k, counts, 2, &s), COAG_INVALID_ARGUMENT);
    lc.struct_size = sizeof lc + 8;
    EXPECT(coag_counts_new(&lc, k, counts, 2, &s), COAG_INVALID_ARGUMENT);
    {
        coag_massflow_config mc;
        OK(coag_massflow_default_config(&mc, sizeof mc));
        mc.struct_size = 3;
        double x[2] = {1.0, 1.0};
        EXPECT(coag_massflow_new(&mc, k, NULL, x, 2, &s), COAG_INVALID_ARGUMENT);
    }

    /* a working sim, then every misuse on it */
    OK(coag_counts_default_config(&lc, sizeof lc));
    lc.size_limit = 64;
    OK(coag_counts_new(&lc, k, counts, 2, &s));
    EXPECT(coag_sim_advance_to(NULL, 1.0, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_advance_to(s, NAN, NULL), COAG_INVALID_ARGUMENT);
    {
        /* a report without its size is refused before the sim moves */
        coag_step_report rep = {0};
        EXPECT(coag_sim_advance_to(s, 0.1, &rep), COAG_INVALID_ARGUMENT);
        OK(coag_sim_time(s, &d));
        CHECK(d == 0.0, "sim unchanged by a refused report: t = %g", d);
        EXPECT(coag_step_report_init(NULL, sizeof rep), COAG_NULL_PARAMETER);
        EXPECT(coag_step_report_init(&rep, 8), COAG_INVALID_ARGUMENT); /* below the first version */
        {
            /* a caller with a larger (newer) report: the known fields are written, nothing past */
            struct {
                coag_step_report r;
                uint64_t extra;
            } big;
            memset(&big, 0xab, sizeof big);
            big.r.struct_size = sizeof big;
            OK(coag_sim_advance_to(s, 0.05, &big.r));
            CHECK(big.r.time == 0.05 && big.extra == 0xababababababababull, "newer report: known fields only");
        }
        OK(coag_step_report_init(&rep, sizeof rep));
        CHECK(rep.struct_size == sizeof rep && rep.events == 0, "report init");
        int method = -1;
        OK(coag_sim_method(s, &method));
        CHECK(method == COAG_METHOD_LOWRANK, "default method is bucketed low-rank: %d", method);
    }
    OK(coag_sim_advance_to(s, 0.5, NULL));
    EXPECT(coag_sim_advance_to(s, 0.25, NULL), COAG_TIME_BACKWARDS);
    OK(coag_sim_time(s, &d));
    CHECK(d == 0.5, "time kept after failures: %g", d);
    EXPECT(coag_sim_time(s, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_moment(s, NAN, &d), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_moment(NULL, 1.0, &d), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_concentration(s, NAN, 2.0, &d), COAG_INVALID_ARGUMENT);
    /* issue 14: C(5, 1) returned -0.0, M_{1e6} inf with COAG_OK */
    d = 42.0;
    EXPECT(coag_sim_concentration(s, 5.0, 1.0, &d), COAG_INVALID_ARGUMENT);
    CHECK(d == 42.0, "output untouched on error");
    OK(coag_sim_concentration(s, 1e9, 1e9, &d));
    CHECK(d == 0.0 && !signbit(d), "an empty range is +0: %g", d);
    EXPECT(coag_sim_moment(s, 1e6, &d), COAG_CAPACITY);
    OK(coag_sim_moment(s, 2.0, &d));
    EXPECT(coag_sim_get_sizes(s, sizes, 4), COAG_UNSUPPORTED); /* not a mass-flow sim */
    EXPECT(coag_sim_set_sizes(s, sizes, 4), COAG_UNSUPPORTED);
    EXPECT(coag_sim_set_dt(s, 0.1), COAG_UNSUPPORTED);
    EXPECT(coag_sim_set_fragmentation(s, NULL), COAG_UNSUPPORTED);
    OK(coag_sim_state_len(s, &z));
    uint64_t one[1];
    EXPECT(coag_sim_get_counts(s, one, 1, &d), z > 1 ? COAG_BUFFER_TOO_SMALL : COAG_OK);
    EXPECT(coag_sim_get_counts(s, NULL, 0, &d), z > 0 ? COAG_BUFFER_TOO_SMALL : COAG_OK);
    EXPECT(coag_sim_set_counts(s, counts, 2, -1.0), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_counts(s, NULL, 2, 1.0), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_set_kernel(s, NULL), COAG_NULL_PARAMETER);
    coag_kernel *bk;
    OK(coag_kernel_new_brownian(&bk)); /* rank 2 into a rank-1 low-rank sim */
    EXPECT(coag_sim_set_kernel(s, bk), COAG_UNSUPPORTED);
    coag_kernel_free(bk);
    /* the size limit of 64 is reached: a capacity error, and the sim still works */
    int st = COAG_OK;
    double t = 0.5;
    while (st == COAG_OK && t < 1e6) {
        t *= 2.0;
        st = coag_sim_advance_to(s, t, NULL);
    }
    CHECK(st == COAG_CAPACITY, "size limit reached: %s", coag_status_name(st));
    OK(coag_sim_particle_count(s, &u));
    CHECK(u >= 1, "still usable after the failure");
    /* checkpoints: sizes, truncation, garbage */
    size_t need;
    OK(coag_sim_checkpoint_size(s, &need));
    uint8_t *buf = malloc(need);
    EXPECT(coag_sim_checkpoint(s, buf, need / 2, &z), COAG_BUFFER_TOO_SMALL);
    EXPECT(coag_sim_checkpoint(s, NULL, need, &z), COAG_NULL_PARAMETER);
    OK(coag_sim_checkpoint(s, buf, need, &z));
    EXPECT(coag_sim_restore(s, buf, need / 2), COAG_BAD_CHECKPOINT);
    buf[40] ^= 0xff;
    int r = coag_sim_restore(s, buf, need);
    CHECK(r == COAG_BAD_CHECKPOINT || r == COAG_OK, "garbage is refused or harmless: %s", coag_status_name(r));
    memset(buf, 0, need);
    EXPECT(coag_sim_restore(s, buf, need), COAG_BAD_CHECKPOINT);
    EXPECT(coag_sim_restore(s, NULL, 0), COAG_BAD_CHECKPOINT);
    free(buf);
    OK(coag_sim_particle_count(s, &u));
    coag_sim_free(s);

    /* a kernel that turns NaN mid-run: INVALID_RATE, then the sim is still usable */
    coag_user_kernel nk2 = {nan_kernel, NULL, 0, NULL, 0, NULL, NULL};
    coag_kernel *nanf;
    OK(coag_kernel_new_user(&nk2, &nanf));
    OK(coag_massflow_default_config(&mc, sizeof mc));
    mc.dt = 0.1;
    double init[64];
    for (int i = 0; i < 64; i++) init[i] = 1.0;
    OK(coag_massflow_new(&mc, nanf, NULL, init, 64, &s));
    st = COAG_OK;
    t = 0.0;
    while (st == COAG_OK && t < 100.0) {
        t += 0.1;
        st = coag_sim_advance_to(s, t, NULL);
    }
    CHECK(st == COAG_INVALID_RATE, "NaN rate reported: %s", coag_status_name(st));
    double before, after;
    OK(coag_sim_moment(s, 2.0, &before));
    EXPECT(coag_sim_advance_to(s, t + 1.0, NULL), COAG_INVALID_RATE);
    OK(coag_sim_moment(s, 2.0, &after));
    CHECK(before == after, "state unchanged by the failed step");
    OK(coag_sim_set_kernel(s, k)); /* repair with a sane kernel and carry on */
    OK(coag_sim_advance_to(s, t + 1.0, NULL));
    double got[64];
    EXPECT(coag_sim_get_sizes(s, got, 63), COAG_BUFFER_TOO_SMALL);
    EXPECT(coag_sim_set_sizes(s, init, 63), COAG_BUFFER_TOO_SMALL);
    init[5] = NAN;
    EXPECT(coag_sim_set_sizes(s, init, 64), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_dt(s, -1.0), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_get_counts(s, &u, 1, NULL), COAG_UNSUPPORTED);
    coag_sim_free(s);
    coag_kernel_free(nanf);
    coag_kernel_free(nk);

    /* frees of NULL are no-ops */
    coag_sim_free(NULL);
    coag_kernel_free(NULL);
    coag_fragmentation_free(NULL);
    coag_kernel_free(k);
    EXPECT(coag_exact_moment(COAG_EXACT_ADDITIVE, 9, 1.0, &d), COAG_UNSUPPORTED);
    EXPECT(coag_exact_density(COAG_EXACT_COAG_FRAG, 1, 1.0, &d), COAG_UNSUPPORTED);
    return finish("test_misuse");
}
