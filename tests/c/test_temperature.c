/* The temperature-dependent low-rank Monte Carlo of the C ABI (Osinsky 2023 §4): the
 * registry schemes "temperature" (the low-rank engine) and "temperature-rejection"
 * (the acceptance-rejection baseline) under the temperature models of core's table.
 * The closed-form model against its exact solution on both schemes, the ballistic
 * model's conservation of mass and its cooling, checkpoints, clones and work-limited
 * calls (split = unbroken, bit for bit), and refusals that leave the sim unchanged.
 * The statistical checks use Student's t for 32 replicas at a two-sided 1e-6 false
 * alarm each: 6.07 standard errors (a factor 2 in a rate is hundreds). */
#include <stdint.h>
#include <string.h>

#include "check.h"

#define Z32 6.07
#define REPS 32
/* under valgrind (test_quick): 8 replicas, Student t at 7 degrees of freedom for the
 * same two-sided 1e-6 (the memory check needs the code paths, the sanitizer run the
 * statistics' power) */
#define Z8 11.21
#define REPS_QUICK 8
/* monomers of the model-family runs (a fifth under valgrind: see test_quick; at 4000,
 * seeds 40-44 gave z from -2.05 to +2.08 on both engines, no sign of bias) */
#define N0_FULL 20000u

/* A sim of `scheme` from n0 monomers at temperature t0 in `volume`. */
static coag_sim *make(const char *scheme, const coag_kernel *k, const coag_options *o, uint64_t n0, double t0,
                      double volume) {
    coag_sim *h = NULL;
    OK(coag_sim_new_temperatures(scheme, k, o, &n0, &t0, 1, volume, &h));
    return h;
}

/* A named observable of a temperature sim. */
static double observe(const coag_sim *h, const char *name) {
    double v = NAN;
    OK(coag_sim_observable(h, name, &v));
    return v;
}

static double moment(const coag_sim *h, double m) {
    double v = NAN;
    OK(coag_sim_moment(h, m, &v));
    return v;
}

/* The state as one array (malloc'ed, length in *len): the occupied sizes, their
 * counts, and their partial temperatures as bits (compared bit for bit). */
static uint64_t *state_of(const coag_sim *h, size_t *len) {
    size_t m = 0, w = 0, wt = 0;
    OK(coag_sim_occupied(h, &m));
    uint64_t *out = malloc((3 * m + 1) * sizeof *out);
    uint64_t *ks = malloc((m + 1) * sizeof *ks);
    double *t = malloc((m + 1) * sizeof *t);
    OK(coag_sim_get_pairs(h, out, out + m, m, NULL, &w));
    OK(coag_sim_size_values(h, "temperature", ks, t, m, &wt));
    CHECK(w == m && wt == m && memcmp(ks, out, m * sizeof *ks) == 0,
          "pairs (%zu) and temperatures (%zu) cover the %zu occupied sizes", w, wt, m);
    memcpy(out + 2 * m, t, m * sizeof *t);
    free(ks);
    free(t);
    *len = 3 * m;
    return out;
}

/* The closed-form model's solution from n_1(0) = n0, T_1(0) = t0 (TEMPERATURE.md; core's
 * ClosedForm::exact): u(t) = [1 + (1 + gamma) c n0 sqrt(t0) t / 2]^(1 / (1 + gamma)),
 * N(t) = n0 / u, mean temperature t0 u^(1 - 2 gamma). */
static void closed_form_exact(double c, double gamma, double n0, double t0, double t, double *number,
                              double *mean_temperature) {
    double g1 = 1.0 + gamma;
    double u = pow(1.0 + g1 * c * n0 * sqrt(t0) * t / 2.0, 1.0 / g1);
    *number = n0 / u;
    *mean_temperature = t0 * pow(u, 1.0 - 2.0 * gamma);
}

int main(void) {
    const uint64_t N0 = test_quick() ? N0_FULL / 5 : N0_FULL;
    /* 1. The closed-form model (c = 1, gamma = 1/2) from n1(0) = 1, T1(0) = 1: N(4) and
     *    the mean temperature (constant for gamma = 1/2) against the exact solution, on
     *    both schemes; some collisions bounce, some aggregate. */
    double n_exact, t_exact;
    closed_form_exact(1.0, 0.5, 1.0, 1.0, 4.0, &n_exact, &t_exact);
    coag_kernel *model = KERNEL2("temperature-closed-form", 1.0, 0.5);
    const char *schemes[2] = {"temperature", "temperature-rejection"};
    for (int e = 0; e < 2; e++) {
        stats sn = {0}, st = {0};
        for (int r = 0; r < (test_quick() ? REPS_QUICK : REPS); r++) {
            coag_options *o = options_seeded(40, (uint64_t)r);
            coag_sim *h = make(schemes[e], model, o, N0, 1.0, (double)N0);
            coag_options_free(o);
            coag_step_report rep;
            OK(coag_step_report_init(&rep, sizeof rep));
            OK(coag_sim_advance_to(h, 4.0, &rep));
            CHECK(rep.bounces > 0 && rep.bounces < rep.events, "bounces %llu of %llu",
                  (unsigned long long)rep.bounces, (unsigned long long)rep.events);
            stats_push(&sn, moment(h, 0.0));
            stats_push(&st, observe(h, "mean-temperature"));
            coag_sim_free(h);
        }
        double zn = (sn.mean - n_exact) / stats_se(&sn), zt = (st.mean - t_exact) / stats_se(&st);
        printf("%s: N(4) %.6f vs %.6f (%+.2f SE), mean T %.6f vs %.6f (%+.2f SE)\n", schemes[e], sn.mean,
               n_exact, zn, st.mean, t_exact, zt);
        const double zmax = test_quick() ? Z8 : Z32;
        CHECK(fabs(zn) < zmax, "%s: N(4) %g SE", schemes[e], zn);
        CHECK(fabs(zt) < zmax, "%s: mean temperature %g SE", schemes[e], zt);
    }
    coag_kernel_free(model);

    /* 2. The paper's ballistic kernels (eps = 0.99, a = 0.1, lambda = 0.4: the table's
     *    defaults): mass is conserved, the gas cools. */
    coag_kernel *ballistic = KERNEL0("temperature-ballistic");
    coag_options *o7 = options_seeded(7, 0);
    double n1 = 0.3 / 3.14159265358979323846;
    coag_sim *h = make("temperature", ballistic, o7, 50000, 1.0, 50000 / n1);
    double m1a = moment(h, 1.0), ea = observe(h, "energy");
    OK(coag_sim_advance_to(h, 50.0, NULL));
    double m1b = moment(h, 1.0), eb = observe(h, "energy"), tb = observe(h, "mean-temperature");
    CHECK(fabs(m1b - m1a) < 1e-12 * m1a, "mass %g -> %g", m1a, m1b);
    CHECK(eb < ea && tb < 1.0 && tb > 0.5, "energy %g -> %g, mean T %g", ea, eb, tb);
    /* the energy density is the mean temperature times the number density */
    CHECK(fabs(eb - tb * moment(h, 0.0)) < 1e-12 * eb, "energy %g vs mean T x M0 %g", eb, tb * moment(h, 0.0));

    /* 3. Checkpoint at t = 50, continue to 80; a new sim restored from it reaches the
     *    same state, bit for bit. */
    size_t need = 0;
    OK(coag_sim_checkpoint_size(h, &need));
    uint8_t *buf = malloc(need);
    size_t wrote = 0;
    EXPECT(coag_sim_checkpoint(h, buf, need - 1, NULL), COAG_BUFFER_TOO_SMALL);
    OK(coag_sim_checkpoint(h, buf, need, &wrote));
    CHECK(wrote == need, "wrote %zu of %zu", wrote, need);
    coag_sim *fork = NULL, *bounded = NULL;
    OK(coag_sim_clone(h, &fork));
    OK(coag_sim_clone(h, &bounded));
    OK(coag_sim_advance_to(h, 80.0, NULL));
    coag_sim *g = make("temperature", ballistic, o7, 10, 1.0, 10.0);
    OK(coag_sim_restore(g, buf, wrote));
    OK(coag_sim_advance_to(g, 80.0, NULL));
    size_t la, lb;
    uint64_t *sa = state_of(h, &la), *sb = state_of(g, &lb);
    CHECK(la == lb && memcmp(sa, sb, la * sizeof *sa) == 0, "restored run differs");
    CHECK(same_sim(h, g), "restored run's checkpoint differs");
    free(sb);
    /* a clone continues as the original; so does a run cut into calls of at most 2000
     * proposals (each COAG_INTERRUPTED at a consistent time, then called again) */
    OK(coag_sim_advance_to(fork, 80.0, NULL));
    CHECK(same_sim(h, fork), "a clone continued differently");
    OK(coag_sim_set_work_limit(bounded, 2000));
    int rc = COAG_INTERRUPTED, calls = 0;
    while (rc == COAG_INTERRUPTED && calls < 100000) {
        rc = coag_sim_advance_to(bounded, 80.0, NULL);
        calls++;
    }
    EXPECT(rc, COAG_OK);
    CHECK(calls > 1 && same_sim(h, bounded), "a run of %d bounded calls differs from the unbroken one", calls);
    coag_sim_free(fork);
    coag_sim_free(bounded);

    /* 4. Refusals, the state unchanged. A checkpoint of another model (restitution
     *    0.9) or of the other engine is refused, and so is a corrupted one. */
    size_t ng0;
    uint8_t *g_before = snapshot(g, &ng0);
    coag_kernel *other_model = KERNEL1("temperature-ballistic", 0.9);
    coag_sim *o = make("temperature", other_model, o7, 10, 1.0, 10.0);
    EXPECT(coag_sim_restore(o, buf, wrote), COAG_BAD_CHECKPOINT);
    coag_sim *rej = make("temperature-rejection", ballistic, o7, 10, 1.0, 10.0);
    EXPECT(coag_sim_restore(rej, buf, wrote), COAG_BAD_CHECKPOINT);
    buf[wrote / 2] ^= 1;
    EXPECT(coag_sim_restore(g, buf, wrote), COAG_BAD_CHECKPOINT);
    sb = state_of(g, &lb);
    CHECK(la == lb && memcmp(sa, sb, la * sizeof *sa) == 0, "a refused restore changed the state");
    /* a target in the past, a NULL sim, a report of an unknown size */
    EXPECT(coag_sim_advance_to(g, 10.0, NULL), COAG_TIME_BACKWARDS);
    EXPECT(coag_sim_advance_to(NULL, 10.0, NULL), COAG_NULL_PARAMETER);
    coag_step_report tiny;
    OK(coag_step_report_init(&tiny, sizeof tiny));
    tiny.struct_size = 3;
    EXPECT(coag_sim_advance_to(g, 90.0, &tiny), COAG_INVALID_ARGUMENT);
    /* buffers one size short */
    size_t m = 0, occ = 0, w = 99;
    OK(coag_sim_state_len(g, &m));
    OK(coag_sim_occupied(g, &occ));
    uint64_t *cbuf = calloc(m + 1, sizeof *cbuf), *kbuf = calloc(occ + 1, sizeof *kbuf);
    double *tbuf = calloc(occ + 1, sizeof *tbuf);
    EXPECT(coag_sim_get_counts(g, cbuf, m - 1, NULL), COAG_BUFFER_TOO_SMALL);
    EXPECT(coag_sim_size_values(g, "temperature", kbuf, tbuf, occ - 1, &w), COAG_BUFFER_TOO_SMALL);
    CHECK(w == 99, "written set on error: %zu", w);
    EXPECT(coag_sim_size_values(g, "temperature", NULL, tbuf, occ, &w), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_size_values(g, "velocity", kbuf, tbuf, occ, &w), COAG_UNSUPPORTED);
    /* the dense counts agree with the pairs */
    OK(coag_sim_get_counts(g, cbuf, m + 1, NULL));
    int dense_ok = cbuf[m] == 0;
    for (size_t i = 0; i < occ; i++) dense_ok &= cbuf[sb[i] - 1] == sb[occ + i];
    CHECK(dense_ok, "dense counts differ from the pairs");
    /* a moment of NaN order; names the temperature schemes do not have; a scheme
     * whose particles carry no velocity */
    double v = -1.0;
    EXPECT(coag_sim_moment(g, NAN, &v), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_observable(g, "momentum-x", &v), COAG_UNSUPPORTED);
    EXPECT(coag_sim_observable(g, "no-such-observable", &v), COAG_UNSUPPORTED);
    CHECK(v == -1.0, "output written on error: %g", v);
    EXPECT(coag_sim_velocities(g, kbuf, tbuf, 0), COAG_UNSUPPORTED);
    /* the state is counts with temperatures: the setters of counts or sizes alone and
     * of a coagulation kernel do not apply */
    uint64_t ones[1] = {10};
    double one_size = 1.0;
    EXPECT(coag_sim_set_counts(g, ones, 1, 10.0), COAG_UNSUPPORTED);
    EXPECT(coag_sim_set_pairs(g, ones, ones, 1, 10.0), COAG_UNSUPPORTED);
    EXPECT(coag_sim_set_sizes(g, &one_size, 1), COAG_UNSUPPORTED);
    EXPECT(coag_sim_set_kernel(g, other_model), COAG_UNSUPPORTED);
    CHECK(sim_is(g, g_before, ng0), "a refused call changed the sim");
    free(cbuf);
    free(kbuf);
    free(tbuf);

    /* constructors: a NaN temperature, a negative volume, NULL counts or temperatures,
     * bad models, an unknown scheme, an option of another scheme, a kernel of another
     * family */
    coag_sim *bad = NULL;
    uint64_t n = 100;
    double t_nan = NAN, t_one = 1.0;
    EXPECT(coag_sim_new_temperatures("temperature", ballistic, NULL, &n, &t_nan, 1, 100.0, &bad),
           COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_new_temperatures("temperature", ballistic, NULL, &n, &t_one, 1, -1.0, &bad),
           COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_new_temperatures("temperature", ballistic, NULL, NULL, &t_one, 1, 100.0, &bad),
           COAG_NULL_PARAMETER);
    EXPECT(coag_sim_new_temperatures("temperature", ballistic, NULL, &n, NULL, 1, 100.0, &bad),
           COAG_NULL_PARAMETER);
    coag_kernel *wrong = NULL;
    EXPECT(coag_kernel_new("temperature-ballistic", (const double[]){0.0}, 1, &wrong), COAG_INVALID_ARGUMENT);
    EXPECT(coag_kernel_new("temperature-bogus", NULL, 0, &wrong), COAG_INVALID_ARGUMENT);
    CHECK(wrong == NULL, "a refused kernel was written");
    EXPECT(coag_sim_new_temperatures("temperature-bogus", ballistic, NULL, &n, &t_one, 1, 100.0, &bad),
           COAG_INVALID_ARGUMENT);
    {
        coag_options *od = options_new();
        OK(coag_options_set_real(od, "dt", 0.5));
        EXPECT(coag_sim_new_temperatures("temperature", ballistic, od, &n, &t_one, 1, 100.0, &bad),
               COAG_UNSUPPORTED);
        coag_options_free(od);
        coag_kernel *kc = KERNEL0("constant"), *gas = KERNEL0("hard-spheres");
        EXPECT(coag_sim_new_temperatures("temperature", kc, NULL, &n, &t_one, 1, 100.0, &bad), COAG_UNSUPPORTED);
        EXPECT(coag_sim_new_temperatures("temperature", gas, NULL, &n, &t_one, 1, 100.0, &bad), COAG_UNSUPPORTED);
        EXPECT(coag_sim_new_counts("temperature", ballistic, NULL, NULL, &n, 1, 100.0, &bad), COAG_UNSUPPORTED);
        coag_kernel_free(kc);
        coag_kernel_free(gas);
        double rate = -1.0;
        EXPECT(coag_kernel_rate(ballistic, 1.0, 1.0, &rate), COAG_UNSUPPORTED);
    }
    CHECK(bad == NULL, "a refused constructor wrote its handle");
    /* no sizes: a valid, empty system, as for every scheme (issue 14): no particles,
     * observables 0, no events */
    {
        coag_sim *empty = NULL;
        OK(coag_sim_new_temperatures("temperature", ballistic, NULL, &n, &t_one, 0, 100.0, &empty));
        coag_step_report rep;
        OK(coag_step_report_init(&rep, sizeof rep));
        OK(coag_sim_advance_to(empty, 1.0, &rep));
        uint64_t np = 99;
        size_t len = 99;
        OK(coag_sim_particle_count(empty, &np));
        OK(coag_sim_state_len(empty, &len));
        double mt = observe(empty, "mean-temperature"), en = observe(empty, "energy"), m0 = moment(empty, 0.0);
        CHECK(np == 0 && len == 0 && rep.events == 0 && mt == 0.0 && en == 0.0 && m0 == 0.0,
              "empty: %llu particles, length %zu, %llu events, mean T %g, energy %g, M0 %g", (unsigned long long)np,
              len, (unsigned long long)rep.events, mt, en, m0);
        coag_sim_free(empty);
    }
    /* the closed-form model takes c > 0 and gamma >= 0 */
    EXPECT(coag_kernel_new("temperature-closed-form", (const double[]){0.0, 0.5}, 2, &wrong),
           COAG_INVALID_ARGUMENT);
    EXPECT(coag_kernel_new("temperature-closed-form", (const double[]){1.0, -0.5}, 2, &wrong),
           COAG_INVALID_ARGUMENT);
    CHECK(wrong == NULL, "a refused kernel was written");

    free(g_before);
    free(sa);
    free(sb);
    free(buf);
    coag_options_free(o7);
    coag_kernel_free(ballistic);
    coag_kernel_free(other_model);
    coag_sim_free(o);
    coag_sim_free(rej);
    coag_sim_free(g);
    coag_sim_free(h);
    coag_sim_free(NULL);
    return finish("test_temperature");
}
