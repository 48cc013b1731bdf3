/* Drives the schemes step by step through the C ABI against exact solutions: the
 * time-driven mass flow and the size-count schemes here, the event-driven schemes over
 * particle sizes in test_particles.c, every scheme of the registry in test_registry.c.
 * Statistical checks use R independent replicas and a tolerance of Z_TOL standard errors
 * (a wrong factor 2 in a rate moves the means by tens of standard errors). */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "check.h"

#define REPLICAS 32
/* Student t with 31 degrees of freedom at the suite's two-sided false-alarm rate 1e-6 per
 * comparison (coagula_core::observe::TEST_ALPHA; student_t_threshold(1e-6, 31)). */
#define Z_TOL 6.072

/* Lécot's coagulation-fragmentation test with QMC points: M2, M3 at t = 0.1 .. 1 within
 * the QMC error plus the Euler bias of P = 100 steps (measured errors are ~1e-3). */
static void massflow_lecot(void) {
    coag_kernel *k = KERNEL1("constant", 1.0);
    coag_fragmentation *f;
    OK(coag_fragmentation_new_binary_uniform(1.0, &f));
    coag_options *o = options_new();
    OK(coag_options_set_real(o, "dt", 0.01));
    enum { N = 1 << 12 };
    static double sizes[N];
    for (int i = 0; i < N; i++) sizes[i] = 1.0;
    coag_sim *s;
    OK(coag_sim_new_sizes("massflow", k, f, o, sizes, N, 1.0, &s));
    coag_kernel_free(k); /* the sim keeps its own copy */
    coag_fragmentation_free(f);
    coag_options_free(o);
    for (int h = 1; h <= 10; h++) {
        double t = 0.1 * h, m2, m3, e2, e3;
        coag_step_report r;
        coag_step_report_init(&r, sizeof r);
        OK(coag_sim_advance_to(s, t, &r));
        CHECK(r.proposals == 10u * N, "one proposal per particle and step, got %llu", (unsigned long long)r.proposals);
        OK(coag_sim_moment(s, 2.0, &m2));
        OK(coag_sim_moment(s, 3.0, &m3));
        OK(coag_exact_moment(COAG_EXACT_COAG_FRAG, 2, t, &e2));
        OK(coag_exact_moment(COAG_EXACT_COAG_FRAG, 3, t, &e3));
        CHECK(fabs(m2 - e2) < 5e-3, "t=%g M2 %g vs %g", t, m2, e2);
        CHECK(fabs(m3 - e3) < 3e-2, "t=%g M3 %g vs %g", t, m3, e3);
    }
    double now;
    OK(coag_sim_time(s, &now));
    CHECK(fabs(now - 1.0) < 1e-12, "time %g", now);
    size_t n;
    OK(coag_sim_state_len(s, &n));
    CHECK(n == N, "state length %zu", n);
    static double buf[N];
    OK(coag_sim_get_sizes(s, buf, N));
    double sum = 0.0, m2;
    for (int i = 0; i < N; i++) sum += buf[i];
    OK(coag_sim_moment(s, 2.0, &m2));
    CHECK(fabs(sum / N - m2) < 1e-12, "M2 = (M1/N) sum x: %g vs %g", sum / N, m2);
    for (int i = 1; i < N; i++) CHECK(buf[i - 1] <= buf[i], "sorted at %d", i);
    const char *name = NULL;
    OK(coag_sim_scheme(s, &name));
    CHECK(name && strcmp(name, "massflow") == 0, "scheme %s", name ? name : "(null)");
    coag_sim_free(s);
}

/* Size-count schemes against the constant-kernel solution M0(2) = 1/2 and n_1(2) = 1/4,
 * with a built-in kernel and with the same kernel written in C. */
static double c_const(double x, double y, void *ud) {
    (void)x;
    (void)y;
    return *(const double *)ud;
}
static void c_const_factors(double x, double *a, double *b, void *ud) {
    (void)x;
    a[0] = 0.5 * *(const double *)ud;
    b[0] = 1.0;
}
static double c_const_majorant(double x, void *ud) {
    (void)x;
    return sqrt(*(const double *)ud);
}
static double c_const_sup(double lo, double hi, void *ud) {
    (void)lo;
    (void)hi;
    return *(const double *)ud;
}

static void counts_schemes(void) {
    static double k0 = 1.0;
    coag_user_kernel uk = {c_const, c_const_majorant, 1, c_const_factors, 1, c_const_sup, &k0};
    coag_kernel *user, *builtin = KERNEL1("constant", 1.0);
    OK(coag_kernel_new_user(&uk, &user));
    const coag_kernel *kernels[2] = {builtin, user};
    /* every coagulation scheme of the registry that starts from counts (a scheme
     * added to the registry is tested here with no edit) */
    const char *schemes[32];
    int ns = 0;
    size_t nreg;
    OK(coag_scheme_count(&nreg));
    for (size_t i = 0; i < nreg; i++) {
        coag_scheme_info info;
        OK(coag_scheme_info_get(i, &info, sizeof info));
        if (info.model == COAG_MODEL_COAGULATION && (info.inits & COAG_INIT_COUNTS) && ns < 32)
            schemes[ns++] = info.name;
    }
    CHECK(ns >= 6, "the registry's counts schemes: %d", ns);
    double e_m0, e_n1;
    OK(coag_exact_moment(COAG_EXACT_CONSTANT, 0, 2.0, &e_m0));
    OK(coag_exact_density(COAG_EXACT_CONSTANT, 1, 2.0, &e_n1));
    for (int ki = 0; ki < 2; ki++) {
        for (int mi = 0; mi < ns; mi++) {
            stats m0 = {0}, n1 = {0};
            for (int r = 0; r < REPLICAS; r++) {
                coag_options *o = options_seeded(1000 + r, 0);
                uint64_t counts[1] = {1 << 13};
                coag_sim *s = sim_counts(schemes[mi], kernels[ki], o, counts, 1, (double)counts[0]);
                coag_options_free(o);
                /* step by step, as a host integrator would */
                for (int h = 1; h <= 20; h++) OK(coag_sim_advance_to(s, 0.1 * h, NULL));
                double v, vol;
                OK(coag_sim_moment(s, 0.0, &v));
                stats_push(&m0, v);
                size_t len;
                OK(coag_sim_state_len(s, &len));
                uint64_t *buf = calloc(len, sizeof *buf);
                OK(coag_sim_get_counts(s, buf, len, &vol));
                stats_push(&n1, (double)buf[0] / vol);
                free(buf);
                coag_step_report tot;
                coag_step_report_init(&tot, sizeof tot);
                OK(coag_sim_totals(s, &tot));
                CHECK(tot.bound_violations == 0, "no violations, got %llu", (unsigned long long)tot.bound_violations);
                coag_sim_free(s);
            }
            CHECK(fabs(m0.mean - e_m0) < Z_TOL * stats_se(&m0), "kernel %d %s: M0 %g ± %g vs %g", ki, schemes[mi],
                  m0.mean, stats_se(&m0), e_m0);
            CHECK(fabs(n1.mean - e_n1) < Z_TOL * stats_se(&n1), "kernel %d %s: n1 %g ± %g vs %g", ki, schemes[mi],
                  n1.mean, stats_se(&n1), e_n1);
        }
    }
    coag_kernel_free(user);
    coag_kernel_free(builtin);
}

/* The engine a sim runs now ("slots", "counted", "blocks"; "" when it has none). */
static const char *engine_of(const coag_sim *s) {
    const char *e = NULL;
    OK(coag_sim_engine(s, &e));
    return e ? e : "";
}

/* A low-rank sim of `n` monomers (volume n) with the `engine` option (NULL: not set). */
static coag_sim *lowrank_sim(const coag_kernel *k, const char *engine, uint64_t seed, uint64_t n) {
    coag_options *o = options_seeded(seed, 0);
    if (engine) OK(coag_options_set_name(o, "engine", engine));
    uint64_t counts[1] = {n};
    coag_sim *s = sim_counts("lowrank", k, o, counts, 1, (double)n);
    coag_options_free(o);
    return s;
}

/* The low-rank method's engines: chosen by size (engine "auto" or not set) and by the
 * kernel (block majorants for a loose low-rank bound), or pinned; each pinned engine against the exact M0(2) of the constant kernel; the pin
 * kept through set_counts and clone; a checkpoint of the other engine refused by a
 * pinned sim. */
static void bucket_engines(void) {
    coag_kernel *k = KERNEL1("constant", 1.0);
    double e_m0;
    OK(coag_exact_moment(COAG_EXACT_CONSTANT, 0, 2.0, &e_m0));
    const char *modes[5] = {NULL, "auto", "slots", "counted", "blocks"};
    /* 8192 particles: the size choice is the counted engine */
    const char *runs[5] = {"counted", "counted", "slots", "counted", "blocks"};
    for (int mi = 0; mi < 5; mi++) {
        stats m0 = {0};
        for (int r = 0; r < REPLICAS; r++) {
            coag_sim *s = lowrank_sim(k, modes[mi], 2000 + r, 1 << 13);
            const char *m = engine_of(s);
            CHECK(strcmp(m, runs[mi]) == 0, "engine %s runs engine %s, expected %s", modes[mi] ? modes[mi] : "unset",
                  m, runs[mi]);
            for (int h = 1; h <= 20; h++) OK(coag_sim_advance_to(s, 0.1 * h, NULL));
            double v;
            OK(coag_sim_moment(s, 0.0, &v));
            stats_push(&m0, v);
            coag_sim_free(s);
        }
        if (mi == 1) continue; /* "auto" is the unset run again */
        CHECK(fabs(m0.mean - e_m0) < Z_TOL * stats_se(&m0), "engine %s: M0 %g ± %g vs %g",
              modes[mi] ? modes[mi] : "unset", m0.mean, stats_se(&m0), e_m0);
    }
    /* by the kernel: the atmospheric kernel's low-rank bound is loose, so block
     * majorants unless pinned */
    coag_kernel *atm = KERNEL1("atmospheric", 1.0);
    uint64_t many[1] = {20000};
    coag_sim *ab = sim_counts("lowrank", atm, NULL, many, 1, 20000.0);
    CHECK(strcmp(engine_of(ab), "blocks") == 0, "atmospheric by kernel: engine %s", engine_of(ab));
    coag_sim *as = lowrank_sim(atm, "slots", 0, 20000);
    CHECK(strcmp(engine_of(as), "slots") == 0, "atmospheric pinned to slots: engine %s", engine_of(as));
    coag_sim_free(ab);
    coag_sim_free(as);
    coag_kernel_free(atm);
    /* by size: 20000 particles run on slots, and a replaced state chooses again; pinned
     * engines stay */
    uint64_t small[1] = {100};
    coag_sim *a = lowrank_sim(k, NULL, 0, 20000);
    CHECK(strcmp(engine_of(a), "slots") == 0, "20000 particles by size: engine %s", engine_of(a));
    OK(coag_sim_set_counts(a, small, 1, 100.0));
    CHECK(strcmp(engine_of(a), "counted") == 0, "100 particles by size: engine %s", engine_of(a));
    coag_sim *p = lowrank_sim(k, "counted", 0, 20000);
    CHECK(strcmp(engine_of(p), "counted") == 0, "pinned counted at 20000: engine %s", engine_of(p));
    coag_sim *q = lowrank_sim(k, "slots", 0, 20000);
    OK(coag_sim_set_counts(q, small, 1, 100.0));
    CHECK(strcmp(engine_of(q), "slots") == 0, "pinned slots after set_counts: engine %s", engine_of(q));
    /* a clone keeps the pin and continues the same run */
    OK(coag_sim_advance_to(q, 0.5, NULL));
    coag_sim *qc;
    OK(coag_sim_clone(q, &qc));
    CHECK(strcmp(engine_of(qc), "slots") == 0, "clone of a pinned sim: engine %s", engine_of(qc));
    OK(coag_sim_advance_to(q, 1.0, NULL));
    OK(coag_sim_advance_to(qc, 1.0, NULL));
    CHECK(same_sim(q, qc), "a clone of a pinned sim ran differently");
    /* (a clone rebuilt by size would take 100 particles onto the counted engine) */
    OK(coag_sim_set_counts(qc, small, 1, 100.0));
    CHECK(strcmp(engine_of(qc), "slots") == 0, "clone of a pinned sim after set_counts: engine %s", engine_of(qc));
    /* the counted engine's checkpoint into a sim pinned to slots: refused, unchanged;
     * into a sim chosen by size: taken (the engine follows the checkpoint) */
    OK(coag_sim_set_counts(a, small, 1, 100.0));
    OK(coag_sim_advance_to(a, 0.25, NULL));
    size_t na, nq0;
    uint8_t *ckpt = snapshot(a, &na);
    uint8_t *before = snapshot(q, &nq0);
    EXPECT(coag_sim_restore(q, ckpt, na), COAG_BAD_CHECKPOINT);
    CHECK(sim_is(q, before, nq0), "a refused restore changed the pinned sim");
    coag_sim *fresh = lowrank_sim(k, NULL, 0, 20000);
    OK(coag_sim_set_counts(fresh, small, 1, 100.0));
    OK(coag_sim_restore(fresh, ckpt, na));
    CHECK(same_sim(a, fresh), "restored by-size sim differs");
    /* bad names; a pin on a scheme without engines; the query on such a sim */
    coag_options *o = options_new();
    EXPECT(coag_options_set_name(o, "engine", "bogus"), COAG_INVALID_ARGUMENT);
    EXPECT(coag_options_set_name(o, "engine", NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_options_set_count(o, "engine", 1), COAG_INVALID_ARGUMENT);
    OK(coag_options_set_name(o, "engine", "slots"));
    coag_sim *none = NULL;
    EXPECT(coag_sim_new_counts("inverse", k, NULL, o, small, 1, 100.0, &none), COAG_UNSUPPORTED);
    CHECK(none == NULL, "a sim from a refused engine");
    coag_options_free(o);
    coag_sim *inv = sim_counts("inverse", k, NULL, small, 1, 100.0);
    const char *m = "untouched";
    EXPECT(coag_sim_engine(inv, &m), COAG_UNSUPPORTED);
    CHECK(strcmp(m, "untouched") == 0, "output written on error");
    EXPECT(coag_sim_engine(NULL, &m), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_engine(a, NULL), COAG_NULL_PARAMETER);
    free(ckpt);
    free(before);
    coag_sim_free(inv);
    coag_sim_free(fresh);
    coag_sim_free(qc);
    coag_sim_free(q);
    coag_sim_free(p);
    coag_sim_free(a);
    coag_kernel_free(k);
}

/* Changing the kernel between steps: K = 1 on [0, 1], K = 2 on [1, 2] gives
 * 1/M0(2) = 1 + 1/2 + 1, i.e. M0 = 0.4 (from M0' = -K M0^2 / 2). */
static void change_kernel_between_steps(void) {
    coag_kernel *k1 = KERNEL1("constant", 1.0), *k2 = KERNEL1("constant", 2.0);
    stats m0 = {0};
    for (int r = 0; r < REPLICAS; r++) {
        coag_options *o = options_seeded(7 + r, 0);
        uint64_t counts[1] = {1 << 13};
        coag_sim *s = sim_counts("lowrank", k1, o, counts, 1, (double)counts[0]);
        coag_options_free(o);
        OK(coag_sim_advance_to(s, 1.0, NULL));
        OK(coag_sim_set_kernel(s, k2));
        OK(coag_sim_advance_to(s, 2.0, NULL));
        double v;
        OK(coag_sim_moment(s, 0.0, &v));
        stats_push(&m0, v);
        coag_sim_free(s);
    }
    CHECK(fabs(m0.mean - 0.4) < Z_TOL * stats_se(&m0), "M0 %g ± %g vs 0.4", m0.mean, stats_se(&m0));
    coag_kernel_free(k1);
    coag_kernel_free(k2);
}

/* A host that owns the randomness: an xorshift64* stream in C. */
static uint64_t host_rng(void *ud) {
    uint64_t *x = ud;
    *x ^= *x >> 12;
    *x ^= *x << 25;
    *x ^= *x >> 27;
    return *x * 0x2545F4914F6CDD1DULL;
}

static void host_randomness(void) {
    coag_kernel *k = KERNEL0("brownian");
    uint64_t finals[2];
    for (int rep = 0; rep < 2; rep++) {
        uint64_t counts[1] = {5000};
        coag_sim *s = sim_counts("lowrank", k, NULL, counts, 1, 5000.0);
        uint64_t state = 0x9E3779B97F4A7C15ULL;
        OK(coag_sim_set_rng_callback(s, host_rng, &state));
        OK(coag_sim_advance_to(s, 1.0, NULL));
        OK(coag_sim_particle_count(s, &finals[rep]));
        CHECK(state != 0x9E3779B97F4A7C15ULL, "the host stream was used");
        coag_sim_free(s);
    }
    CHECK(finals[0] == finals[1], "same host stream, same result: %llu vs %llu", (unsigned long long)finals[0],
          (unsigned long long)finals[1]);
    coag_kernel_free(k);
}

/* A run saved and restored mid-way equals the run without a break, bit for bit. */
static void checkpoint_restore(void) {
    coag_kernel *k = KERNEL2("free-molecular", 1.0, 1.0); /* bounds for integer sizes */
    coag_options *o = options_seeded(99, 0);
    uint64_t counts[1] = {20000};
    coag_sim *a = sim_counts("lowrank", k, o, counts, 1, 20000.0);
    coag_sim *b = sim_counts("lowrank", k, o, counts, 1, 20000.0);
    coag_options_free(o);
    OK(coag_sim_advance_to(a, 1.0, NULL));
    size_t need, written;
    OK(coag_sim_checkpoint_size(a, &need));
    uint8_t *buf = malloc(need);
    EXPECT(coag_sim_checkpoint(a, buf, need - 1, &written), COAG_BUFFER_TOO_SMALL);
    OK(coag_sim_checkpoint(a, buf, need, &written));
    CHECK(written == need, "wrote %zu of %zu", written, need);
    OK(coag_sim_advance_to(a, 3.0, NULL));
    OK(coag_sim_restore(b, buf, written));
    OK(coag_sim_advance_to(b, 3.0, NULL));
    size_t la, lb;
    OK(coag_sim_state_len(a, &la));
    OK(coag_sim_state_len(b, &lb));
    CHECK(la == lb, "state lengths %zu %zu", la, lb);
    uint64_t *ca = calloc(la, 8), *cb = calloc(lb, 8);
    double va, vb;
    OK(coag_sim_get_counts(a, ca, la, &va));
    OK(coag_sim_get_counts(b, cb, lb, &vb));
    CHECK(memcmp(ca, cb, la * 8) == 0 && va == vb, "restored run differs");
    CHECK(same_sim(a, b), "restored run's checkpoint differs");
    free(ca);
    free(cb);
    free(buf);
    coag_sim_free(a);
    coag_sim_free(b);
    coag_kernel_free(k);

    /* the same for RQMC mass flow, whose randomisation must match */
    coag_kernel *kc = KERNEL1("constant", 1.0);
    coag_fragmentation *f;
    OK(coag_fragmentation_new_binary_uniform(1.0, &f));
    coag_options *mo = options_seeded(5, 0);
    OK(coag_options_set_name(mo, "randomization", "owen"));
    double init[1024];
    for (int i = 0; i < 1024; i++) init[i] = 1.0;
    OK(coag_sim_new_sizes("massflow", kc, f, mo, init, 1024, 1.0, &a));
    OK(coag_sim_new_sizes("massflow", kc, f, mo, init, 1024, 1.0, &b));
    OK(coag_sim_advance_to(a, 0.3, NULL));
    buf = snapshot(a, &need);
    OK(coag_sim_advance_to(a, 0.8, NULL));
    OK(coag_sim_restore(b, buf, need));
    OK(coag_sim_advance_to(b, 0.8, NULL));
    double xa[1024], xb[1024];
    OK(coag_sim_get_sizes(a, xa, 1024));
    OK(coag_sim_get_sizes(b, xb, 1024));
    CHECK(memcmp(xa, xb, sizeof xa) == 0, "restored mass-flow run differs");
    /* another randomisation (the scrambling of another seed) refuses the checkpoint, or
     * takes it whole: the restored sim then continues as the run that wrote it */
    coag_sim *other;
    OK(coag_options_set_count(mo, "seed", 6));
    OK(coag_sim_new_sizes("massflow", kc, f, mo, init, 1024, 1.0, &other));
    int st = coag_sim_restore(other, buf, need);
    if (st == COAG_OK) {
        OK(coag_sim_advance_to(other, 0.8, NULL));
        OK(coag_sim_get_sizes(other, xb, 1024));
        CHECK(memcmp(xa, xb, sizeof xa) == 0, "a checkpoint taken by a sim of another scrambling continues differently");
    } else {
        EXPECT(st, COAG_BAD_CHECKPOINT);
    }
    coag_sim_free(other);
    /* another point set is another setting: refused */
    OK(coag_options_set_count(mo, "seed", 5));
    OK(coag_options_set_name(mo, "randomization", "shift"));
    OK(coag_sim_new_sizes("massflow", kc, f, mo, init, 1024, 1.0, &other));
    EXPECT(coag_sim_restore(other, buf, need), COAG_BAD_CHECKPOINT);
    coag_sim_free(other);
    coag_options_free(mo);
    free(buf);
    coag_sim_free(a);
    coag_sim_free(b);
    coag_kernel_free(kc);
    coag_fragmentation_free(f);
}

/* A host applying nucleation between steps: 1000 monomers added at t = 1. */
static void host_modifies_state(void) {
    coag_kernel *k = KERNEL1("constant", 1.0);
    uint64_t counts[1] = {10000};
    coag_sim *s = sim_counts("lowrank", k, NULL, counts, 1, 10000.0);
    OK(coag_sim_advance_to(s, 1.0, NULL));
    size_t len;
    OK(coag_sim_state_len(s, &len));
    uint64_t *buf = calloc(len, 8);
    double vol, m1a, m1b;
    OK(coag_sim_get_counts(s, buf, len, &vol));
    OK(coag_sim_moment(s, 1.0, &m1a));
    buf[0] += 1000;
    OK(coag_sim_set_counts(s, buf, len, vol));
    OK(coag_sim_moment(s, 1.0, &m1b));
    CHECK(fabs(m1b - m1a - 1000.0 / vol) < 1e-12, "mass after nucleation %g vs %g", m1b, m1a + 1000.0 / vol);
    OK(coag_sim_advance_to(s, 2.0, NULL));
    double m1c;
    OK(coag_sim_moment(s, 1.0, &m1c));
    CHECK(fabs(m1c - m1b) < 1e-9, "coagulation conserves mass: %g vs %g", m1c, m1b);
    free(buf);
    coag_sim_free(s);
    coag_kernel_free(k);
}

/* The mass-flow sim in the caller's workspace runs bit for bit like the one that
 * allocates its own, and a too small, misaligned or overlapping workspace is refused
 * (before it is touched). */
static void massflow_in_caller_workspace(void) {
    enum { NP = 1024 };
    coag_kernel *k = KERNEL1("constant", 1.0);
    coag_fragmentation *f;
    OK(coag_fragmentation_new_binary_uniform(1.0, &f));
    coag_options *o = options_seeded(17, 0);
    OK(coag_options_set_name(o, "randomization", "owen"));
    double sizes[NP];
    for (int i = 0; i < NP; i++) sizes[i] = 1.0;
    size_t bytes = 0;
    OK(coag_sim_workspace_size("massflow", f, o, NP, &bytes));
    CHECK(bytes == 6 * NP * sizeof(double), "workspace %zu bytes", bytes);
    EXPECT(coag_sim_workspace_size("massflow", f, o, NP, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_workspace_size("lowrank", NULL, NULL, NP, &bytes), COAG_UNSUPPORTED);
    EXPECT(coag_sim_workspace_size("no-such-scheme", NULL, NULL, NP, &bytes), COAG_INVALID_ARGUMENT);
    double *ws = malloc(bytes);
    coag_sim *own, *in = NULL;
    OK(coag_sim_new_sizes("massflow", k, f, o, sizes, NP, 1.0, &own));
    EXPECT(coag_sim_new_sizes_in("massflow", k, f, o, sizes, NP, 1.0, ws, bytes - 8, &in), COAG_BUFFER_TOO_SMALL);
    EXPECT(coag_sim_new_sizes_in("massflow", k, f, o, sizes, NP, 1.0, (char *)ws + 4, bytes - 8, &in),
           COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_new_sizes_in("massflow", k, f, o, sizes, NP, 1.0, NULL, bytes, &in), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_new_sizes_in("massflow", k, f, o, ws, NP, 1.0, ws, bytes, &in), COAG_INVALID_ARGUMENT); /* overlap */
    {
        /* a set-up refused before the workspace is used leaves it as it was */
        for (size_t i = 0; i < bytes / sizeof(double); i++) ws[i] = 7.0;
        EXPECT(coag_sim_new_sizes_in("massflow", NULL, f, o, sizes, NP, 1.0, ws, bytes, &in), COAG_NULL_PARAMETER);
        EXPECT(coag_sim_new_sizes_in("massflow", k, f, o, sizes, NP, 1.0, ws, bytes / 2, &in), COAG_BUFFER_TOO_SMALL);
        CHECK(ws[0] == 7.0 && ws[bytes / sizeof(double) - 1] == 7.0, "workspace untouched by a refused call");
        CHECK(in == NULL, "a sim from a refused workspace");
    }
    OK(coag_sim_new_sizes_in("massflow", k, f, o, sizes, NP, 1.0, ws, bytes, &in));
    for (int h = 1; h <= 30; h++) {
        OK(coag_sim_advance_to(own, 0.05 * h, NULL));
        OK(coag_sim_advance_to(in, 0.05 * h, NULL));
    }
    double a[NP], b[NP];
    OK(coag_sim_get_sizes(own, a, NP));
    OK(coag_sim_get_sizes(in, b, NP));
    CHECK(memcmp(a, b, sizeof a) == 0, "caller workspace run differs");
    CHECK(same_sim(own, in), "caller workspace checkpoint differs");
    double m2;
    OK(coag_sim_moment(in, 2.0, &m2));
    CHECK(m2 > 1.0 && m2 < 3.0, "M2 %g", m2);
    /* a clone of the workspace sim lives in the library's memory and runs on */
    coag_sim *cl;
    OK(coag_sim_clone(in, &cl));
    coag_sim_free(in);
    memset(ws, 0xff, bytes); /* the clone does not use it */
    OK(coag_sim_advance_to(own, 2.0, NULL));
    OK(coag_sim_advance_to(cl, 2.0, NULL));
    CHECK(same_sim(own, cl), "clone of a workspace sim differs");
    coag_sim_free(cl);
    coag_sim_free(own);
    free(ws);
    coag_options_free(o);
    coag_kernel_free(k);
    coag_fragmentation_free(f);
}

/* The additive kernel from C, with its low-rank factors (K = x·1 + 1·y), its supremum on
 * a square, and two block suprema: the exact one (the larger corner) and one below the
 * kernel (the smaller corner). */
static double c_add(double x, double y, void *u) {
    (void)u;
    return x + y;
}
static void c_add_factors(double x, double *a, double *b, void *u) {
    (void)u;
    a[0] = x;
    b[0] = 1.0;
}
static double c_add_sup(double lo, double hi, void *u) {
    (void)u;
    (void)lo;
    return 2.0 * hi;
}
static double c_add_block(double x0, double x1, double y0, double y1, void *u) {
    (void)u;
    (void)x0;
    (void)y0;
    return x1 + y1;
}
static double c_add_block_low(double x0, double x1, double y0, double y1, void *u) {
    (void)u;
    (void)x1;
    (void)y1;
    return x0 + y0;
}

/* The counts and events of a sim after it ran to t. */
static void run_counts(coag_sim *s, double t, uint64_t *counts, size_t len, uint64_t *events) {
    OK(coag_sim_advance_to(s, t, NULL));
    double vol;
    size_t n;
    OK(coag_sim_state_len(s, &n));
    CHECK(n <= len, "state of %zu sizes", n);
    memset(counts, 0, len * sizeof *counts);
    OK(coag_sim_get_counts(s, counts, n, &vol));
    coag_step_report tot;
    coag_step_report_init(&tot, sizeof tot);
    OK(coag_sim_totals(s, &tot));
    *events = tot.events;
}

/* A user kernel's supremum over blocks (coag_kernel_set_user_blocks): with the exact
 * block supremum of the additive kernel, lowrank-blocks runs a C kernel to the same
 * counts and events as the built-in kernel for a seed (the default, the supremum on the
 * square around a block, proposes differently); declared loose, `lowrank` picks block
 * majorants; a block bound below the kernel fails the step with COAG_INVALID_RATE;
 * refusals leave the handle as it was. */
static void user_block_suprema(void) {
    coag_user_kernel uk = {c_add, NULL, 1, c_add_factors, 0, c_add_sup, NULL};
    coag_kernel *user = NULL;
    OK(coag_kernel_new_user(&uk, &user));
    coag_kernel *builtin = KERNEL1("additive", 1.0);
    uint64_t start[1] = {2000};
    enum { LEN = 4096 };
    static uint64_t a[LEN], b[LEN];
    uint64_t ea, eb;
    coag_options *o = options_seeded(7, 0);
    coag_sim *sb = sim_counts("lowrank-blocks", builtin, o, start, 1, 2000.0);
    run_counts(sb, 0.6, b, LEN, &eb);
    /* the default block bound (the square's): a valid run, other proposals */
    coag_sim *sq = sim_counts("lowrank-blocks", user, o, start, 1, 2000.0);
    run_counts(sq, 0.6, a, LEN, &ea);
    CHECK(memcmp(a, b, sizeof a) != 0, "the square's bound drew the built-in's proposals");
    /* the exact block supremum: the built-in's bits */
    OK(coag_kernel_set_user_blocks(user, c_add_block, 0));
    coag_sim *su = sim_counts("lowrank-blocks", user, o, start, 1, 2000.0);
    run_counts(su, 0.6, a, LEN, &ea);
    CHECK(ea == eb && ea > 500 && memcmp(a, b, sizeof a) == 0, "C block supremum: %llu events vs %llu",
          (unsigned long long)ea, (unsigned long long)eb);
    /* not loose: lowrank keeps its low-rank engine; loose: block majorants */
    coag_sim *l0 = sim_counts("lowrank", user, o, start, 1, 2000.0);
    CHECK(strcmp(engine_of(l0), "blocks") != 0, "a tight user kernel on %s", engine_of(l0));
    OK(coag_kernel_set_user_blocks(user, c_add_block, 1));
    coag_sim *l1 = sim_counts("lowrank", user, o, start, 1, 2000.0);
    CHECK(strcmp(engine_of(l1), "blocks") == 0, "a loose user kernel on %s", engine_of(l1));
    /* a block bound below the kernel: the step fails, the sim as before the failing
     * event (the books agree with the particles, the mass is whole; the own random
     * stream moves, so a second call runs on to the next violation) */
    OK(coag_kernel_set_user_blocks(user, c_add_block_low, 0));
    coag_sim *bad = sim_counts("lowrank-blocks", user, o, start, 1, 2000.0);
    for (int i = 0; i < 2; i++) {
        EXPECT(coag_sim_advance_to(bad, 0.6, NULL), COAG_INVALID_RATE);
        double tm, m1;
        uint64_t np;
        OK(coag_sim_time(bad, &tm));
        OK(coag_sim_particle_count(bad, &np));
        OK(coag_sim_moment(bad, 1.0, &m1));
        coag_step_report tot;
        coag_step_report_init(&tot, sizeof tot);
        OK(coag_sim_totals(bad, &tot));
        CHECK(tm < 0.6 && tot.events == 2000 - np && m1 == 1.0, "after a violation: t %g, %llu particles, %llu events, M1 %g",
              tm, (unsigned long long)np, (unsigned long long)tot.events, m1);
    }
    /* refusals */
    EXPECT(coag_kernel_set_user_blocks(NULL, c_add_block, 0), COAG_NULL_PARAMETER);
    EXPECT(coag_kernel_set_user_blocks(builtin, c_add_block, 0), COAG_UNSUPPORTED);
    coag_sim *free_list[6] = {sb, sq, su, l0, l1, bad};
    for (int i = 0; i < 6; i++) coag_sim_free(free_list[i]);
    coag_options_free(o);
    coag_kernel_free(user);
    coag_kernel_free(builtin);
}

int main(void) {
    printf("libcoagula %s\n", coag_version());
    massflow_in_caller_workspace();
    massflow_lecot();
    counts_schemes();
    bucket_engines();
    user_block_suprema();
    change_kernel_between_steps();
    host_randomness();
    checkpoint_restore();
    host_modifies_state();
    return finish("test_schemes");
}
