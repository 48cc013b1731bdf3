/* The temperature-dependent low-rank Monte Carlo of the C ABI (Osinsky 2023 §4): the
 * model family against its closed form on both engines, the ballistic model's
 * conservation of mass and its cooling, checkpoints (split = unbroken, bit for bit),
 * and refusals that leave the simulation unchanged. The statistical checks use
 * Student's t for 32 replicas at a two-sided 1e-6 false alarm each: 6.07 standard
 * errors (a factor 2 in a rate is hundreds). */
#include <stdint.h>
#include <string.h>

#include "check.h"

#define Z32 6.07
#define REPS 32
/* monomers of the model-family runs (a fifth under valgrind: see test_quick; at 4000,
 * seeds 40-44 gave z from -2.05 to +2.08 on both engines, no sign of bias) */
#define N0_FULL 20000u

static coag_thermal *make(const coag_thermal_config *c, uint64_t n0, double t0, double volume) {
    coag_thermal *h = NULL;
    OK(coag_thermal_new(c, &n0, &t0, 1, volume, &h));
    return h;
}

/* Copies counts and temperatures (as bits) into one array; returns its length. */
static size_t state_of(const coag_thermal *h, uint64_t *out, size_t cap) {
    size_t m = 0;
    OK(coag_thermal_info(h, NULL, NULL, NULL, &m));
    if (2 * m > cap) {
        fprintf(stderr, "state larger than %zu\n", cap);
        exit(1);
    }
    double *t = malloc(m * sizeof *t);
    OK(coag_thermal_state(h, out, t, m));
    memcpy(out + m, t, m * sizeof *t);
    free(t);
    return 2 * m;
}

int main(void) {
    const uint64_t N0 = test_quick() ? N0_FULL / 5 : N0_FULL;
    /* 1. The model family (c = 1, gamma = 1/2) from n1(0) = 1, T1(0) = 1: N(4) and the
     *    mean temperature against the closed form, on both engines. */
    double n_exact, t_exact;
    OK(coag_thermal_model_exact(1.0, 0.5, 1.0, 1.0, 4.0, &n_exact, &t_exact));
    const int engines[2] = {COAG_THERMAL_LOWRANK, COAG_THERMAL_REJECTION};
    for (int e = 0; e < 2; e++) {
        stats sn = {0}, st = {0};
        for (int r = 0; r < REPS; r++) {
            coag_thermal_config c;
            OK(coag_thermal_default_config(&c, sizeof c));
            c.kernel = COAG_THERMAL_MODEL;
            c.model_c = 1.0;
            c.model_gamma = 0.5;
            c.engine = engines[e];
            c.seed = 40;
            c.stream = (uint64_t)r;
            coag_thermal *h = make(&c, N0, 1.0, (double)N0);
            coag_step_report rep;
            OK(coag_step_report_init(&rep, sizeof rep));
            OK(coag_thermal_advance_to(h, 4.0, &rep));
            CHECK(rep.bounces > 0 && rep.bounces < rep.events, "bounces %llu of %llu",
                  (unsigned long long)rep.bounces, (unsigned long long)rep.events);
            double m0, tm;
            OK(coag_thermal_observe(h, 0.0, &m0, &tm, NULL));
            stats_push(&sn, m0);
            stats_push(&st, tm);
            coag_thermal_free(h);
        }
        double zn = (sn.mean - n_exact) / stats_se(&sn), zt = (st.mean - t_exact) / stats_se(&st);
        printf("engine %d: N(4) %.6f vs %.6f (%+.2f SE), mean T %.6f vs %.6f (%+.2f SE)\n", e,
               sn.mean, n_exact, zn, st.mean, t_exact, zt);
        CHECK(fabs(zn) < Z32, "engine %d: N(4) %g SE", e, zn);
        CHECK(fabs(zt) < Z32, "engine %d: mean temperature %g SE", e, zt);
    }

    /* 2. The paper's ballistic kernels: mass is conserved, the gas cools. */
    coag_thermal_config c;
    OK(coag_thermal_default_config(&c, sizeof c));
    c.seed = 7;
    double n1 = 0.3 / 3.14159265358979323846;
    coag_thermal *h = make(&c, 50000, 1.0, 50000 / n1);
    double m1a, ea;
    OK(coag_thermal_observe(h, 1.0, &m1a, NULL, &ea));
    OK(coag_thermal_advance_to(h, 50.0, NULL));
    double m1b, eb, tb;
    OK(coag_thermal_observe(h, 1.0, &m1b, &tb, &eb));
    CHECK(fabs(m1b - m1a) < 1e-12 * m1a, "mass %g -> %g", m1a, m1b);
    CHECK(eb < ea && tb < 1.0 && tb > 0.5, "energy %g -> %g, mean T %g", ea, eb, tb);

    /* 3. Checkpoint at t = 50, continue to 80; a new handle restored from it reaches
     *    the same state, bit for bit. */
    size_t need = 0;
    OK(coag_thermal_checkpoint_size(h, &need));
    uint8_t *buf = malloc(need);
    size_t wrote = 0;
    EXPECT(coag_thermal_save(h, buf, need - 1, NULL), COAG_BUFFER_TOO_SMALL);
    OK(coag_thermal_save(h, buf, need, &wrote));
    CHECK(wrote == need, "wrote %zu of %zu", wrote, need);
    OK(coag_thermal_advance_to(h, 80.0, NULL));
    coag_thermal *g = make(&c, 10, 1.0, 10.0);
    OK(coag_thermal_restore(g, buf, wrote));
    OK(coag_thermal_advance_to(g, 80.0, NULL));
    static uint64_t sa[1 << 16], sb[1 << 16];
    size_t la = state_of(h, sa, 1 << 16), lb = state_of(g, sb, 1 << 16);
    CHECK(la == lb && memcmp(sa, sb, la * sizeof *sa) == 0, "restored run differs");

    /* 4. Refusals, the state unchanged. */
    coag_thermal_config other = c;
    other.restitution = 0.9;
    coag_thermal *o = make(&other, 10, 1.0, 10.0);
    EXPECT(coag_thermal_restore(o, buf, wrote), COAG_BAD_CHECKPOINT);
    buf[wrote / 2] ^= 1;
    EXPECT(coag_thermal_restore(g, buf, wrote), COAG_BAD_CHECKPOINT);
    lb = state_of(g, sb, 1 << 16);
    CHECK(la == lb && memcmp(sa, sb, la * sizeof *sa) == 0, "a refused restore changed the state");
    EXPECT(coag_thermal_advance_to(g, 10.0, NULL), COAG_TIME_BACKWARDS);
    EXPECT(coag_thermal_advance_to(NULL, 10.0, NULL), COAG_NULL_PARAMETER);
    size_t m = 0;
    OK(coag_thermal_info(g, NULL, NULL, NULL, &m));
    uint64_t small[4];
    EXPECT(coag_thermal_state(g, small, NULL, m + 1), COAG_BUFFER_TOO_SMALL);
    EXPECT(coag_thermal_observe(g, NAN, NULL, NULL, NULL), COAG_INVALID_ARGUMENT);

    coag_thermal *bad = NULL;
    uint64_t n = 100;
    double t_nan = NAN, t_one = 1.0;
    EXPECT(coag_thermal_new(&c, &n, &t_nan, 1, 100.0, &bad), COAG_INVALID_ARGUMENT);
    EXPECT(coag_thermal_new(&c, &n, &t_one, 1, -1.0, &bad), COAG_INVALID_ARGUMENT);
    EXPECT(coag_thermal_new(&c, &n, &t_one, 0, 100.0, &bad), COAG_INVALID_ARGUMENT);
    EXPECT(coag_thermal_new(&c, NULL, &t_one, 1, 100.0, &bad), COAG_NULL_PARAMETER);
    coag_thermal_config wrong = c;
    wrong.restitution = 0.0;
    EXPECT(coag_thermal_new(&wrong, &n, &t_one, 1, 100.0, &bad), COAG_INVALID_ARGUMENT);
    wrong = c;
    wrong.kernel = 7;
    EXPECT(coag_thermal_new(&wrong, &n, &t_one, 1, 100.0, &bad), COAG_INVALID_ARGUMENT);
    wrong = c;
    wrong.engine = -1;
    EXPECT(coag_thermal_new(&wrong, &n, &t_one, 1, 100.0, &bad), COAG_INVALID_ARGUMENT);
    wrong = c;
    wrong.struct_size = 3;
    EXPECT(coag_thermal_new(&wrong, &n, &t_one, 1, 100.0, &bad), COAG_INVALID_ARGUMENT);
    CHECK(bad == NULL, "a refused constructor wrote its handle");
    EXPECT(coag_thermal_model_exact(0.0, 0.5, 1.0, 1.0, 1.0, NULL, NULL), COAG_INVALID_ARGUMENT);

    free(buf);
    coag_thermal_free(o);
    coag_thermal_free(g);
    coag_thermal_free(h);
    coag_thermal_free(NULL);
    return finish("test_thermal");
}
