/* Issue 12's defects as a C process simulator met them: a kernel that turns NaN
 * mid-run must not lose mass (inverse method, and every size-count scheme that takes
 * such a kernel), a kernel above its declared bound is an error rather than a silently
 * capped rate (every low-rank scheme), and a checkpoint taken before the size table grew
 * restores into a grown sim and continues (no COAG_PANIC). */
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
    uint64_t *c = calloc(len ? len : 1, sizeof *c);
    double v;
    OK(coag_sim_get_counts(s, c, len, &v));
    uint64_t m = 0;
    for (size_t i = 0; i < len; i++) m += (uint64_t)(i + 1) * c[i];
    free(c);
    return m;
}

/* item 8: the inverse method, NaN for x + y > 4: reported, and the mass kept (up to
 * particle doubling). The same for every other size-count coagulation scheme that
 * takes a kernel with no bounds. */
static void nan_kernel_keeps_mass(void) {
    coag_user_kernel desc = {nan_beyond_4, NULL, 0, NULL, 0, NULL, NULL};
    coag_kernel *nk;
    OK(coag_kernel_new_user(&desc, &nk));
    size_t n;
    OK(coag_scheme_count(&n));
    int tried_inverse = 0;
    for (size_t i = 0; i < n; i++) {
        coag_scheme_info info;
        OK(coag_scheme_info_get(i, &info, sizeof info));
        if (info.model != COAG_MODEL_COAGULATION || !(info.inits & COAG_INIT_COUNTS)) continue;
        uint64_t counts[1] = {1000};
        coag_sim *s = NULL;
        int st = coag_sim_new_counts(info.name, nk, NULL, NULL, counts, 1, 1000.0, &s);
        /* (the schemes that need a bound refuse a kernel without one) */
        if (strcmp(info.name, "inverse") != 0 && st == COAG_UNSUPPORTED) continue;
        EXPECT(st, COAG_OK);
        if (st != COAG_OK) continue;
        tried_inverse += strcmp(info.name, "inverse") == 0;
        double t = 0.0;
        while (st == COAG_OK && t < 100.0) {
            t += 0.01;
            st = coag_sim_advance_to(s, t, NULL);
        }
        CHECK(st == COAG_INVALID_RATE, "%s: NaN reported: %s", info.name, coag_status_name(st));
        uint64_t m = mass_of(s);
        CHECK(m % 1000 == 0 && ((m / 1000) & (m / 1000 - 1)) == 0, "%s: mass %llu conserved up to doubling",
              info.name, (unsigned long long)m);
        coag_sim_free(s);
    }
    CHECK(tried_inverse == 1, "the inverse method was not run");
    coag_kernel_free(nk);
}

/* item 9: a kernel above its declared low-rank bound: COAG_INVALID_RATE before any
 * event, the sim as before the event (the header's contract: time, particles, moments;
 * no event in the books). (The own random stream and the proposal count do move: the
 * contract is "as before the failing event", not "as before the call" as for
 * COAG_RNG_FAILURE.) */
static void kernel_above_its_bound(void) {
    coag_user_kernel over = {twice_product, NULL, 1, half_product_factors, 0, NULL, NULL};
    coag_kernel *ok;
    OK(coag_kernel_new_user(&over, &ok));
    const char *lowrank[3] = {"lowrank", "lowrank-tree", "lowrank-binary-tree"};
    for (int m = 0; m < 4; m++) {
        coag_sim *s = NULL;
        const char *name = m < 3 ? lowrank[m] : "lowrank-sizes";
        if (m < 3) {
            uint64_t counts[1] = {1000};
            OK(coag_sim_new_counts(name, ok, NULL, NULL, counts, 1, 1000.0, &s));
        } else {
            /* low-rank over sizes: 1000 monomers in volume 1000 */
            double x[1000];
            for (int i = 0; i < 1000; i++) x[i] = 1.0;
            OK(coag_sim_new_sizes(name, ok, NULL, NULL, x, 1000, 1.0, &s));
        }
        double mb[3], ma[3];
        for (int j = 0; j < 3; j++) OK(coag_sim_moment(s, j, &mb[j]));
        EXPECT(coag_sim_advance_to(s, 0.3, NULL), COAG_INVALID_RATE);
        double tm = -1.0;
        OK(coag_sim_time(s, &tm));
        CHECK(tm == 0.0, "%s: time unchanged: %g", name, tm);
        uint64_t n = 0;
        OK(coag_sim_particle_count(s, &n));
        CHECK(n == 1000, "%s: no event applied: %llu particles", name, (unsigned long long)n);
        for (int j = 0; j < 3; j++) OK(coag_sim_moment(s, j, &ma[j]));
        CHECK(memcmp(ma, mb, sizeof ma) == 0, "%s: moments changed by the refused event", name);
        coag_step_report tot;
        OK(coag_step_report_init(&tot, sizeof tot));
        OK(coag_sim_totals(s, &tot));
        CHECK(tot.events == 0, "%s: %llu events booked", name, (unsigned long long)tot.events);
        coag_sim_free(s);
    }
    coag_kernel_free(ok);
}

/* item 7: restore a small-M checkpoint into the grown sim, then grow again */
static void restore_into_grown_sim(void) {
    coag_kernel *add = KERNEL2("additive", 1.0, 1.0); /* bounds for integer sizes */
    uint64_t mono[1] = {2000};
    coag_sim *s = sim_counts("lowrank", add, NULL, mono, 1, 2000.0);
    OK(coag_sim_advance_to(s, 0.1, NULL));
    size_t need;
    OK(coag_sim_checkpoint_size(s, &need));
    uint8_t *buf = malloc(need);
    size_t written;
    OK(coag_sim_checkpoint(s, buf, need, &written));
    OK(coag_sim_advance_to(s, 3.0, NULL));
    uint64_t grown_mass = mass_of(s);
    size_t ng;
    uint8_t *grown = snapshot(s, &ng);
    OK(coag_sim_restore(s, buf, written));
    OK(coag_sim_advance_to(s, 3.0, NULL)); /* used to be COAG_PANIC */
    CHECK(mass_of(s) == grown_mass, "the same run again: mass %llu vs %llu", (unsigned long long)mass_of(s),
          (unsigned long long)grown_mass);
    CHECK(sim_is(s, grown, ng), "the restored run differs from the first");
    free(grown);
    free(buf);
    coag_sim_free(s);
    coag_kernel_free(add);
}

int main(void) {
    nan_kernel_keeps_mass();
    kernel_above_its_bound();
    restore_into_grown_sim();
    return finish("test_regressions");
}
