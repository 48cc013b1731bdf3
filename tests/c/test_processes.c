/* Sources, removal and growth beside coagulation through the one handle: the books
 * balance on every scheme that takes them; a scheme that does not refuses and stays as
 * it was; a checkpoint restores only into a sim with the same processes, and a split
 * run (and a clone) keeps the bits of an unbroken one. */
#include "check.h"

static const char *SCHEMES[] = {"lowrank", "lowrank-tree", "lowrank-binary-tree", "inverse",
                                "rejection", "dsa-counts"};

static coag_sim *make(const char *scheme, int with_processes) {
    coag_kernel *k = KERNEL0("constant");
    coag_options *o = options_seeded(21, 0);
    uint64_t counts[2] = {300, 40};
    coag_sim *sim = sim_counts(scheme, k, o, counts, 2, 300.0);
    coag_options_free(o);
    coag_kernel_free(k);
    if (with_processes) {
        OK(coag_sim_set_source(sim, 0.5, COAG_SOURCE_EXPONENTIAL, 2.0, 0.0));
        OK(coag_sim_set_removal(sim, 0.1, 1.0 / 3.0));
        OK(coag_sim_set_growth(sim, 0.05, 1.0));
    }
    return sim;
}

/* a host's rate per particle: the double user_data points to */
static double host_rate(double x, void *ud) {
    (void)x;
    return *(const double *)ud;
}

static size_t save(coag_sim *sim, uint8_t **out) {
    size_t len, written;
    OK(coag_sim_checkpoint_size(sim, &len));
    *out = malloc(len);
    OK(coag_sim_checkpoint(sim, *out, len, &written));
    return written;
}

static int same_state(coag_sim *a, coag_sim *b) {
    uint8_t *x, *y;
    size_t lx = save(a, &x), ly = save(b, &y);
    int same = lx == ly && memcmp(x, y, lx) == 0;
    free(x);
    free(y);
    return same;
}

static void books_balance(coag_sim *sim, const char *scheme) {
    coag_books b;
    memset(&b, 0, sizeof b);
    b.struct_size = sizeof b;
    OK(coag_sim_books(sim, &b));
    uint64_t n;
    double m0, m1;
    OK(coag_sim_particle_count(sim, &n));
    OK(coag_sim_moment(sim, 0.0, &m0));
    OK(coag_sim_moment(sim, 1.0, &m1));
    CHECK(b.initial_number + b.injected_number - b.removed_number - b.merged == n,
          "%s: the number", scheme);
    double mass = b.initial_mass + b.injected_mass - b.removed_mass + b.grown_mass;
    CHECK(fabs(mass - m1 * (double)n / m0) < 1e-9 * mass, "%s: the mass %g vs %g", scheme, mass,
          m1 * (double)n / m0);
    CHECK(b.injected_number > 0 && b.removed_number > 0 && b.grown_mass > 0, "%s: every process acted",
          scheme);
}

int main(void) {
    for (size_t i = 0; i < sizeof SCHEMES / sizeof *SCHEMES; i++) {
        const char *s = SCHEMES[i];
        coag_sim *whole = make(s, 1);
        OK(coag_sim_advance_to(whole, 3.0, NULL));
        books_balance(whole, s);
        /* split through checkpoints into fresh sims */
        coag_sim *split = make(s, 1);
        double stops[3] = {0.4, 1.3, 2.2};
        for (int j = 0; j < 3; j++) {
            OK(coag_sim_advance_to(split, stops[j], NULL));
            uint8_t *buf;
            size_t len = save(split, &buf);
            coag_sim *bare = make(s, 0);
            EXPECT(coag_sim_restore(bare, buf, len), COAG_BAD_CHECKPOINT);
            coag_sim_free(bare);
            coag_sim *fresh = make(s, 1);
            OK(coag_sim_restore(fresh, buf, len));
            free(buf);
            coag_sim_free(split);
            split = fresh;
        }
        OK(coag_sim_advance_to(split, 3.0, NULL));
        CHECK(same_state(whole, split), "%s: split = unbroken", s);
        coag_sim *copy;
        OK(coag_sim_clone(whole, &copy));
        OK(coag_sim_advance_to(whole, 4.0, NULL));
        OK(coag_sim_advance_to(copy, 4.0, NULL));
        CHECK(same_state(whole, copy), "%s: a clone continues identically", s);
        coag_sim_free(copy);
        coag_sim_free(split);
        coag_sim_free(whole);
    }
    /* the mass flow runs them in its own steps: its books balance with the mass it
       carries (M1), the number is its N; MFA refuses them; then refusals on real
       sizes and bad parameters */
    coag_kernel *k = KERNEL0("constant");
    double sizes[64];
    for (int i = 0; i < 64; i++) sizes[i] = 1.0 + i % 3;
    coag_sim *mf;
    OK(coag_sim_new_sizes("massflow", k, NULL, NULL, sizes, 64, 1.0, &mf));
    OK(coag_sim_set_source(mf, 0.5, COAG_SOURCE_EXPONENTIAL, 2.0, 0.0));
    OK(coag_sim_set_removal(mf, 0.1, 0.5));
    OK(coag_sim_set_growth(mf, 0.2, 1.0 / 3.0));
    EXPECT(coag_sim_set_growth_step(mf, 0.1), COAG_UNSUPPORTED);
    OK(coag_sim_advance_to(mf, 1.0, NULL));
    {
        coag_books b;
        memset(&b, 0, sizeof b);
        b.struct_size = sizeof b;
        OK(coag_sim_books(mf, &b));
        double m1;
        OK(coag_sim_moment(mf, 1.0, &m1));
        double mass = b.initial_mass + b.injected_mass - b.removed_mass + b.grown_mass;
        CHECK(fabs(mass - m1) < 1e-12 * m1, "massflow: books %.17g vs M1 %.17g", mass, m1);
        CHECK(b.initial_number == 64 && b.injected_number == 0 && b.merged == 0,
              "massflow: the number is N");
        CHECK(b.injected_mass > 0.9 && b.removed_mass > 0 && b.grown_mass > 0,
              "massflow: every process acted");
    }
    coag_sim_free(mf);
    OK(coag_sim_new_sizes("mfa", k, NULL, NULL, sizes, 64, 1.0, &mf));
    EXPECT(coag_sim_set_removal(mf, 0.1, 0.0), COAG_UNSUPPORTED);
    coag_sim_free(mf);
    coag_sim *ls;
    OK(coag_sim_new_sizes("lowrank-sizes", k, NULL, NULL, sizes, 64, 1.0, &ls));
    EXPECT(coag_sim_set_growth(ls, 0.1, 0.0), COAG_UNSUPPORTED);
    {
        /* growth on real sizes: split of the step set first; linear growth with the
           constant kernel gives M1 = M1(0) e^{gt} at the step's multiples, exactly;
           between them the half step not yet taken */
        coag_sim *gs;
        OK(coag_sim_new_sizes("lowrank-sizes", k, NULL, NULL, sizes, 64, 1.0, &gs));
        EXPECT(coag_sim_set_growth_step(gs, 0.0), COAG_INVALID_ARGUMENT);
        OK(coag_sim_set_growth_step(gs, 0.25));
        OK(coag_sim_set_growth(gs, 0.2, 1.0));
        double g0, g1, g2;
        OK(coag_sim_moment(gs, 1.0, &g0));
        OK(coag_sim_advance_to(gs, 2.0, NULL));
        OK(coag_sim_moment(gs, 1.0, &g1));
        CHECK(fabs(g1 - g0 * exp(0.4)) < 1e-12 * g1, "split growth: M1 %.15g vs %.15g", g1, g0 * exp(0.4));
        OK(coag_sim_advance_to(gs, 2.1, NULL));
        OK(coag_sim_moment(gs, 1.0, &g2));
        CHECK(fabs(g2 - g1) < 1e-12 * g1, "no growth before (k + 1/2) step: %.15g", g2);
        coag_sim_free(gs);
    }
    OK(coag_sim_set_removal(ls, 0.1, 0.0));
    EXPECT(coag_sim_set_removal(ls, 0.1, 1.5), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_source(ls, -1.0, COAG_SOURCE_MONODISPERSE, 1.0, 0.0), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_source(ls, 1.0, COAG_SOURCE_LOGNORMAL, 1.0, 0.5), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_source(NULL, 1.0, COAG_SOURCE_MONODISPERSE, 1.0, 0.0), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_set_growth_step(NULL, 0.5), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_set_growth_step(ls, NAN), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_growth_step(ls, INFINITY), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_source_callback(NULL, host_rate, NULL, 1.0, 0), COAG_NULL_PARAMETER);
    {
        /* a schedule: off until t = 1, then on; before a source is set: refused */
        coag_sim *q = make("lowrank", 0);
        double st[2] = {1.0, 2.0}, sr[2] = {0.0, 0.5};
        EXPECT(coag_sim_set_source_schedule(q, st, sr, 2), COAG_INVALID_ARGUMENT);
        OK(coag_sim_set_source(q, 5.0, COAG_SOURCE_MONODISPERSE, 1.0, 0.0));
        OK(coag_sim_set_source_schedule(q, st, sr, 2));
        OK(coag_sim_advance_to(q, 1.0, NULL));
        coag_books qb;
        memset(&qb, 0, sizeof qb);
        qb.struct_size = sizeof qb;
        OK(coag_sim_books(q, &qb));
        CHECK(qb.injected_number > 1000, "the rate before the schedule's first time: %llu",
              (unsigned long long)qb.injected_number);
        uint64_t before = qb.injected_number;
        double late[2] = {1.0, 9.0}, off[2] = {0.0, 0.0};
        OK(coag_sim_set_source_schedule(q, late, off, 2));
        OK(coag_sim_advance_to(q, 3.0, NULL));
        OK(coag_sim_books(q, &qb));
        CHECK(qb.injected_number == 0, "a schedule that is off: nothing injected (%llu, %llu before)",
              (unsigned long long)qb.injected_number, (unsigned long long)before);
        sr[0] = NAN;
        EXPECT(coag_sim_set_source_schedule(q, st, sr, 2), COAG_INVALID_ARGUMENT);
        EXPECT(coag_sim_set_source_schedule(q, st, NULL, 2), COAG_NULL_PARAMETER);
        coag_sim_free(q);
    }
    {
        /* a host's removal rate, a quarter of its bound: the books balance; a rate
         * above the bound refuses the advance and leaves the sim as it was */
        coag_sim *q = make("lowrank", 1);
        static double lam = 0.25;
        OK(coag_sim_set_removal_callback(q, host_rate, &lam, 1.0, 11));
        OK(coag_sim_advance_to(q, 2.0, NULL));
        books_balance(q, "lowrank with a host removal");
        /* (the host rate alone: a retry meets the same candidate) */
        OK(coag_sim_clear_processes(q));
        OK(coag_sim_set_removal_callback(q, host_rate, &lam, 0.2, 11));
        coag_sim *copy;
        OK(coag_sim_clone(q, &copy));
        EXPECT(coag_sim_advance_to(q, 20.0, NULL), COAG_INVALID_RATE);
        double tq;
        OK(coag_sim_time(q, &tq));
        EXPECT(coag_sim_advance_to(q, 30.0, NULL), COAG_INVALID_RATE);
        double tq2;
        OK(coag_sim_time(q, &tq2));
        CHECK(tq2 == tq, "a refused event leaves the sim where it stood (%.17g, %.17g)", tq, tq2);
        EXPECT(coag_sim_set_removal_callback(q, host_rate, &lam, NAN, 11), COAG_INVALID_ARGUMENT);
        EXPECT(coag_sim_set_growth_callback(q, host_rate, &lam, 0.0, 11), COAG_INVALID_ARGUMENT);
        OK(coag_sim_set_removal_callback(q, NULL, NULL, 1.0, 0));
        OK(coag_sim_advance_to(q, 20.0, NULL));
        coag_sim_free(copy);
        coag_sim_free(q);
    }
    {
        /* a host's source rate as a function of time: refused without a source; with
         * one, S = 0.25 against a bound 4 times higher injects Poisson(S V t) = 300
         * monomers in V = 300 over t = 4 (not 1200: the thinning); above its bound the
         * advance is refused; NULL goes back to the source's own rate */
        coag_sim *q = make("lowrank", 0);
        static double s_rate = 0.25;
        EXPECT(coag_sim_set_source_callback(q, host_rate, &s_rate, 1.0, 12), COAG_INVALID_ARGUMENT);
        OK(coag_sim_set_source(q, 50.0, COAG_SOURCE_MONODISPERSE, 1.0, 0.0));
        EXPECT(coag_sim_set_source_callback(q, host_rate, &s_rate, NAN, 12), COAG_INVALID_ARGUMENT);
        OK(coag_sim_set_source_callback(q, host_rate, &s_rate, 1.0, 12));
        OK(coag_sim_advance_to(q, 4.0, NULL));
        coag_books fb;
        memset(&fb, 0, sizeof fb);
        fb.struct_size = sizeof fb;
        OK(coag_sim_books(q, &fb));
        CHECK(fabs((double)fb.injected_number - 300.0) < 6.0 * sqrt(300.0), "source function: %llu injected",
              (unsigned long long)fb.injected_number);
        uint64_t fn_count;
        OK(coag_sim_particle_count(q, &fn_count));
        CHECK(fb.initial_number + fb.injected_number - fb.removed_number - fb.merged == fn_count,
              "source function: the books give the number");
        OK(coag_sim_set_source_callback(q, host_rate, &s_rate, 0.1, 12));
        EXPECT(coag_sim_advance_to(q, 10.0, NULL), COAG_INVALID_RATE);
        OK(coag_sim_set_source_callback(q, NULL, NULL, 0.0, 0));
        OK(coag_sim_advance_to(q, 10.0, NULL));
        coag_sim_free(q);
    }
    double listed[3] = {1.0, 2.5, 2.5};
    OK(coag_sim_set_source_sizes(ls, 0.5, listed, 3));
    listed[1] = NAN;
    EXPECT(coag_sim_set_source_sizes(ls, 0.5, listed, 3), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_source_sizes(ls, 0.5, NULL, 3), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_set_source_sizes(ls, 0.5, listed, 1), COAG_BUFFER_TOO_SMALL);
    EXPECT(coag_sim_books(ls, NULL), COAG_NULL_PARAMETER);
    coag_books small;
    small.struct_size = 4;
    EXPECT(coag_sim_books(ls, &small), COAG_INVALID_ARGUMENT);
    coag_sim_free(ls);
    coag_kernel_free(k);
    printf("test_processes: %d checks, %d failed\n", checks, failures);
    return failures != 0;
}
