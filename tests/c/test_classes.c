/* Host coupling on size classes through the one handle: the projection keeps number and
 * mass on every kind of population; a population built from class numbers has them
 * (mass exactly on a mass flow, counts within one particle elsewhere); the same seed
 * gives the same bits; bad input is refused and leaves the sim as it was. */
#include "check.h"

#define NP 24

static void pivots_fill(double *x) {
    for (int i = 0; i < 8; i++) x[i] = i + 1;
    for (int i = 8; i < NP; i++) x[i] = floor(x[i - 1] * 1.5 + 0.5);
}

static double mass_of(const double *x, const double *n) {
    double m = 0.0;
    for (int i = 0; i < NP; i++) m += x[i] * n[i];
    return m;
}

static double sum_of(const double *n) {
    double s = 0.0;
    for (int i = 0; i < NP; i++) s += n[i];
    return s;
}

/* project, check number and mass against the moments, build back, project again */
static void round_trip(coag_sim *sim, const char *what, int mass_flow) {
    double x[NP], n[NP], back[NP], out[4];
    pivots_fill(x);
    OK(coag_sim_advance_to(sim, 1.5, NULL));
    OK(coag_sim_project(sim, x, NP, n, out));
    double m0, m1;
    OK(coag_sim_moment(sim, 0.0, &m0));
    OK(coag_sim_moment(sim, 1.0, &m1));
    /* the volume, for the count check: N / M0 */
    uint64_t np;
    OK(coag_sim_particle_count(sim, &np));
    double v = (double)np / m0;
    double nn = sum_of(n) + out[0] + out[2], mm = mass_of(x, n) + out[1] + out[3];
    CHECK(fabs(nn / m0 - 1.0) < 1e-12, "%s: number %g vs M0 %g", what, nn, m0);
    CHECK(fabs(mm / m1 - 1.0) < 1e-12, "%s: mass %g vs M1 %g", what, mm, m1);
    CHECK(out[0] == 0.0 && out[1] == 0.0, "%s: nothing below the first pivot", what);
    OK(coag_sim_set_classes(sim, x, n, NP));
    OK(coag_sim_project(sim, x, NP, back, NULL));
    if (mass_flow) {
        CHECK(fabs(mass_of(x, back) / mass_of(x, n) - 1.0) < 1e-12, "%s: the mass exactly", what);
    } else {
        int ok = 1;
        for (int i = 0; i < NP; i++) ok &= fabs(back[i] - n[i]) * v <= 1.0 + 1e-9;
        CHECK(ok, "%s: every class within one particle", what);
    }
    OK(coag_sim_advance_to(sim, 2.0, NULL));
}

int main(void) {
    coag_kernel *k = KERNEL0("constant");
    const char *counts_schemes[] = {"lowrank", "inverse", "dsa-counts"};
    for (size_t i = 0; i < 3; i++) {
        coag_options *o = options_seeded(5, i);
        uint64_t c[1] = {2048};
        coag_sim *s = sim_counts(counts_schemes[i], k, o, c, 1, 2048.0);
        round_trip(s, counts_schemes[i], 0);
        coag_sim_free(s);
        coag_options_free(o);
    }
    static double ones[2048];
    for (int i = 0; i < 2048; i++) ones[i] = 1.0;
    const char *size_schemes[] = {"massflow", "mfa", "dsa"};
    for (size_t i = 0; i < 3; i++) {
        coag_options *o = options_seeded(6, i);
        coag_sim *s;
        OK(coag_sim_new_sizes(size_schemes[i], k, NULL, o, ones, 2048, 1.0, &s));
        round_trip(s, size_schemes[i], i < 2);
        coag_sim_free(s);
        coag_options_free(o);
    }

    /* same seed, same bits */
    double x[NP], n[NP];
    pivots_fill(x);
    for (int i = 0; i < NP; i++) n[i] = 0.013 * (i + 1);
    coag_sim *a, *b;
    {
        coag_options *o = options_seeded(9, 1);
        uint64_t c[1] = {100};
        a = sim_counts("lowrank", k, o, c, 1, 100.0);
        b = sim_counts("lowrank", k, o, c, 1, 100.0);
        coag_options_free(o);
    }
    OK(coag_sim_set_classes(a, x, n, NP));
    OK(coag_sim_set_classes(b, x, n, NP));
    CHECK(same_sim(a, b), "same seed, same population from classes");

    /* refusals leave the sim unchanged */
    size_t len;
    uint8_t *before = snapshot(a, &len);
    double bad[NP];
    memcpy(bad, n, sizeof bad);
    bad[3] = NAN;
    EXPECT(coag_sim_set_classes(a, x, bad, NP), COAG_INVALID_ARGUMENT);
    bad[3] = -1.0;
    EXPECT(coag_sim_set_classes(a, x, bad, NP), COAG_INVALID_ARGUMENT);
    double down[NP];
    memcpy(down, x, sizeof down);
    down[5] = down[4];
    EXPECT(coag_sim_set_classes(a, down, n, NP), COAG_INVALID_ARGUMENT);
    double half[2] = {1.0, 2.5}, two[2] = {0.1, 0.1};
    EXPECT(coag_sim_set_classes(a, half, two, 2), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_classes(a, NULL, n, NP), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_set_classes(a, x, NULL, NP), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_set_classes(NULL, x, n, NP), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_set_classes(a, x, n, 0), COAG_BUFFER_TOO_SMALL);
    CHECK(sim_is(a, before, len), "refused classes leave the sim unchanged");
    double got[NP];
    for (int i = 0; i < NP; i++) got[i] = 42.0;
    EXPECT(coag_sim_project(a, down, NP, got, NULL), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_project(a, x, NP, NULL, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_project(a, x, NP, x, NULL), COAG_INVALID_ARGUMENT);
    CHECK(got[0] == 42.0 && got[NP - 1] == 42.0, "a refused projection writes nothing");
    free(before);

    /* rates: (after - before) / dt, in place allowed */
    double r0[3] = {1.0, 2.0, 3.0}, r1[3] = {2.0, 2.0, 1.0}, r[3];
    OK(coag_class_rates(r0, r1, 3, 0.5, r));
    CHECK(r[0] == 2.0 && r[1] == 0.0 && r[2] == -4.0, "rates");
    OK(coag_class_rates(r0, r1, 3, 0.5, r1));
    CHECK(r1[0] == 2.0 && r1[2] == -4.0, "rates in place");
    EXPECT(coag_class_rates(r0, r1, 3, 0.0, r), COAG_INVALID_ARGUMENT);
    EXPECT(coag_class_rates(r0, NULL, 3, 1.0, r), COAG_NULL_PARAMETER);

    /* core's sectional reference: refusals leave it as it was */
    coag_sectional *sec = NULL;
    EXPECT(coag_sectional_new(NULL, x, NP, &sec), COAG_NULL_PARAMETER);
    EXPECT(coag_sectional_new(k, x, NP, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_sectional_new(k, down, NP, &sec), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sectional_new(k, x, 0, &sec), COAG_BUFFER_TOO_SMALL);
    OK(coag_sectional_new(k, x, NP, &sec));
    OK(coag_sectional_add(sec, 1.0, 1.0));
    EXPECT(coag_sectional_add(sec, 1e9, 1.0), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sectional_add(sec, 1.0, NAN), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sectional_set_numbers(sec, bad, NP), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sectional_set_numbers(sec, n, NP - 1), COAG_BUFFER_TOO_SMALL);
    EXPECT(coag_sectional_set_processes(sec, -1.0, 1.0, 0.0, 0.0, 0.0, 0.0), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sectional_set_processes(sec, 1.0, 1.0, NAN, 0.0, 0.0, 0.0), COAG_INVALID_RATE);
    EXPECT(coag_sectional_advance_to(sec, 1.0, 0.0), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sectional_advance_to(NULL, 1.0, 0.1), COAG_NULL_PARAMETER);
    double m = -1.0, tt = -1.0;
    EXPECT(coag_sectional_moment(sec, NAN, &m, &tt), COAG_INVALID_ARGUMENT);
    OK(coag_sectional_moment(sec, 1.0, &m, &tt));
    CHECK(m == 1.0 && tt == 0.0, "refusals left the sectional solution as it was");
    coag_sectional_free(sec);
    coag_sectional_free(NULL);

    coag_sim_free(b);
    coag_sim_free(a);
    coag_kernel_free(k);
    return finish("test_classes");
}
