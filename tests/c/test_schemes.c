/* Drives every scheme step by step through the C ABI against exact solutions.
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
    coag_kernel *k;
    coag_fragmentation *f;
    OK(coag_kernel_new_constant(1.0, &k));
    OK(coag_fragmentation_new_binary_uniform(1.0, &f));
    coag_massflow_config c;
    OK(coag_massflow_default_config(&c, sizeof c));
    c.dt = 0.01;
    enum { N = 1 << 12 };
    static double sizes[N];
    for (int i = 0; i < N; i++) sizes[i] = 1.0;
    coag_sim *s;
    OK(coag_massflow_new(&c, k, f, sizes, N, &s));
    coag_kernel_free(k); /* the sim keeps its own copy */
    coag_fragmentation_free(f);
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
    coag_kernel *user, *builtin;
    OK(coag_kernel_new_user(&uk, &user));
    OK(coag_kernel_new_constant(1.0, &builtin));
    const coag_kernel *kernels[2] = {builtin, user};
    const int methods[5] = {COAG_METHOD_LOWRANK, COAG_METHOD_LOWRANK_TREE, COAG_METHOD_INVERSE,
                            COAG_METHOD_REJECTION, COAG_METHOD_DSA_COUNTS};
    double e_m0, e_n1;
    OK(coag_exact_moment(COAG_EXACT_CONSTANT, 0, 2.0, &e_m0));
    OK(coag_exact_density(COAG_EXACT_CONSTANT, 1, 2.0, &e_n1));
    for (int ki = 0; ki < 2; ki++) {
        for (int mi = 0; mi < 5; mi++) {
            stats m0 = {0}, n1 = {0};
            for (int r = 0; r < REPLICAS; r++) {
                coag_counts_config c;
                OK(coag_counts_default_config(&c, sizeof c));
                c.method = methods[mi];
                c.seed = 1000 + r;
                uint64_t counts[1] = {1 << 13};
                coag_sim *s;
                OK(coag_counts_new(&c, kernels[ki], counts, 1, &s));
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
            CHECK(fabs(m0.mean - e_m0) < Z_TOL * stats_se(&m0), "kernel %d method %d: M0 %g ± %g vs %g", ki, mi,
                  m0.mean, stats_se(&m0), e_m0);
            CHECK(fabs(n1.mean - e_n1) < Z_TOL * stats_se(&n1), "kernel %d method %d: n1 %g ± %g vs %g", ki, mi,
                  n1.mean, stats_se(&n1), e_n1);
        }
    }
    coag_kernel_free(user);
    coag_kernel_free(builtin);
}

/* A checkpoint of `s` (malloc'ed; length in *n). */
static uint8_t *snapshot(coag_sim *s, size_t *n) {
    OK(coag_sim_checkpoint_size(s, n));
    uint8_t *b = malloc(*n);
    OK(coag_sim_checkpoint(s, b, *n, NULL));
    return b;
}

/* Whether two sims hold the same checkpoint (state, stream, configuration). */
static int same_sim(coag_sim *a, coag_sim *b) {
    size_t na, nb;
    uint8_t *x = snapshot(a, &na), *y = snapshot(b, &nb);
    int eq = na == nb && memcmp(x, y, na) == 0;
    free(x);
    free(y);
    return eq;
}

/* Whether two sims hold the same particle sizes. */
static int same_sizes(coag_sim *a, coag_sim *b) {
    size_t la, lb;
    OK(coag_sim_state_len(a, &la));
    OK(coag_sim_state_len(b, &lb));
    if (la != lb) return 0;
    double *xa = malloc((la + 1) * sizeof *xa), *xb = malloc((la + 1) * sizeof *xb);
    OK(coag_sim_get_sizes(a, xa, la));
    OK(coag_sim_get_sizes(b, xb, la));
    int eq = memcmp(xa, xb, la * sizeof *xa) == 0;
    free(xa);
    free(xb);
    return eq;
}

/* The bucketed low-rank method's two engines: chosen by size (COAG_BUCKET_AUTO) or pinned;
 * each pinned engine against the exact M0(2) of the constant kernel; the pin kept through
 * set_counts and clone; a checkpoint of the other engine refused by a pinned sim. */
static void bucket_engines(void) {
    coag_kernel *k;
    OK(coag_kernel_new_constant(1.0, &k));
    double e_m0;
    OK(coag_exact_moment(COAG_EXACT_CONSTANT, 0, 2.0, &e_m0));
    const int modes[3] = {COAG_BUCKET_AUTO, COAG_BUCKET_SLOTS, COAG_BUCKET_COUNTED};
    /* 8192 particles: the size choice is the counted engine */
    const int runs[3] = {COAG_BUCKET_COUNTED, COAG_BUCKET_SLOTS, COAG_BUCKET_COUNTED};
    for (int mi = 0; mi < 3; mi++) {
        stats m0 = {0};
        for (int r = 0; r < REPLICAS; r++) {
            coag_counts_config c;
            OK(coag_counts_default_config(&c, sizeof c));
            CHECK(c.bucket_mode == COAG_BUCKET_AUTO, "default bucket_mode %d", c.bucket_mode);
            c.bucket_mode = modes[mi];
            c.seed = 2000 + r;
            uint64_t counts[1] = {1 << 13};
            coag_sim *s;
            OK(coag_counts_new(&c, k, counts, 1, &s));
            int m = -1;
            OK(coag_sim_bucket_mode(s, &m));
            CHECK(m == runs[mi], "bucket_mode %d runs engine %d, expected %d", modes[mi], m, runs[mi]);
            for (int h = 1; h <= 20; h++) OK(coag_sim_advance_to(s, 0.1 * h, NULL));
            double v;
            OK(coag_sim_moment(s, 0.0, &v));
            stats_push(&m0, v);
            coag_sim_free(s);
        }
        CHECK(fabs(m0.mean - e_m0) < Z_TOL * stats_se(&m0), "bucket_mode %d: M0 %g ± %g vs %g", modes[mi], m0.mean,
              stats_se(&m0), e_m0);
    }
    /* by size: 20000 particles run on slots, and a replaced state chooses again; pinned
     * engines stay */
    uint64_t big[1] = {20000}, small[1] = {100};
    coag_counts_config c;
    OK(coag_counts_default_config(&c, sizeof c));
    coag_sim *a, *p, *q;
    int m = -1;
    OK(coag_counts_new(&c, k, big, 1, &a));
    OK(coag_sim_bucket_mode(a, &m));
    CHECK(m == COAG_BUCKET_SLOTS, "20000 particles by size: engine %d", m);
    OK(coag_sim_set_counts(a, small, 1, 100.0));
    OK(coag_sim_bucket_mode(a, &m));
    CHECK(m == COAG_BUCKET_COUNTED, "100 particles by size: engine %d", m);
    c.bucket_mode = COAG_BUCKET_COUNTED;
    OK(coag_counts_new(&c, k, big, 1, &p));
    OK(coag_sim_bucket_mode(p, &m));
    CHECK(m == COAG_BUCKET_COUNTED, "pinned counted at 20000: engine %d", m);
    c.bucket_mode = COAG_BUCKET_SLOTS;
    OK(coag_counts_new(&c, k, big, 1, &q));
    OK(coag_sim_set_counts(q, small, 1, 100.0));
    OK(coag_sim_bucket_mode(q, &m));
    CHECK(m == COAG_BUCKET_SLOTS, "pinned slots after set_counts: engine %d", m);
    /* a clone keeps the pin and continues the same run */
    OK(coag_sim_advance_to(q, 0.5, NULL));
    coag_sim *qc;
    OK(coag_sim_clone(q, &qc));
    OK(coag_sim_bucket_mode(qc, &m));
    CHECK(m == COAG_BUCKET_SLOTS, "clone of a pinned sim: engine %d", m);
    OK(coag_sim_advance_to(q, 1.0, NULL));
    OK(coag_sim_advance_to(qc, 1.0, NULL));
    CHECK(same_sim(q, qc), "a clone of a pinned sim ran differently");
    /* (a clone rebuilt by size would take 100 particles onto the counted engine) */
    OK(coag_sim_set_counts(qc, small, 1, 100.0));
    OK(coag_sim_bucket_mode(qc, &m));
    CHECK(m == COAG_BUCKET_SLOTS, "clone of a pinned sim after set_counts: engine %d", m);
    /* the counted engine's checkpoint into a sim pinned to slots: refused, unchanged;
     * into a sim chosen by size: taken (the engine follows the checkpoint) */
    OK(coag_sim_set_counts(a, small, 1, 100.0));
    OK(coag_sim_advance_to(a, 0.25, NULL));
    size_t na, nq0, nq1;
    uint8_t *ckpt = snapshot(a, &na);
    uint8_t *before = snapshot(q, &nq0);
    EXPECT(coag_sim_restore(q, ckpt, na), COAG_BAD_CHECKPOINT);
    uint8_t *after = snapshot(q, &nq1);
    CHECK(nq0 == nq1 && memcmp(before, after, nq0) == 0, "a refused restore changed the pinned sim");
    coag_sim *fresh;
    c.bucket_mode = COAG_BUCKET_AUTO;
    OK(coag_counts_new(&c, k, big, 1, &fresh));
    OK(coag_sim_set_counts(fresh, small, 1, 100.0));
    OK(coag_sim_restore(fresh, ckpt, na));
    CHECK(same_sim(a, fresh), "restored by-size sim differs");
    /* a caller built before bucket_mode existed passes the smaller struct_size, with
     * garbage where the field now is: it gets COAG_BUCKET_AUTO */
    {
        coag_counts_config old;
        memset(&old, 0xab, sizeof old);
        OK(coag_counts_default_config(&old, sizeof old));
        old.struct_size = offsetof(coag_counts_config, bucket_mode);
        old.reserved = 0x7777;
        old.bucket_mode = 12345;
        coag_sim *o;
        OK(coag_counts_new(&old, k, small, 1, &o));
        OK(coag_sim_bucket_mode(o, &m));
        CHECK(m == COAG_BUCKET_COUNTED, "an older caller's sim: engine %d", m);
        coag_counts_config back;
        OK(coag_sim_counts_config(o, &back, sizeof back));
        CHECK(back.bucket_mode == COAG_BUCKET_AUTO && back.reserved == 0, "older caller's config %d %d",
              back.bucket_mode, back.reserved);
        coag_sim_free(o);
    }
    /* bad codes; a pin on a method without engines; the query on such a sim */
    coag_sim *none = NULL;
    c.bucket_mode = 3;
    EXPECT(coag_counts_new(&c, k, small, 1, &none), COAG_INVALID_ARGUMENT);
    c.bucket_mode = -1;
    EXPECT(coag_counts_new(&c, k, small, 1, &none), COAG_INVALID_ARGUMENT);
    c.bucket_mode = COAG_BUCKET_SLOTS;
    c.method = COAG_METHOD_INVERSE;
    EXPECT(coag_counts_new(&c, k, small, 1, &none), COAG_INVALID_ARGUMENT);
    CHECK(none == NULL, "a sim from a refused bucket_mode");
    c.bucket_mode = COAG_BUCKET_AUTO;
    coag_sim *inv;
    OK(coag_counts_new(&c, k, small, 1, &inv));
    m = 42;
    EXPECT(coag_sim_bucket_mode(inv, &m), COAG_UNSUPPORTED);
    CHECK(m == 42, "output written on error");
    EXPECT(coag_sim_bucket_mode(NULL, &m), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_bucket_mode(a, NULL), COAG_NULL_PARAMETER);
    free(ckpt);
    free(before);
    free(after);
    coag_sim_free(inv);
    coag_sim_free(fresh);
    coag_sim_free(qc);
    coag_sim_free(q);
    coag_sim_free(p);
    coag_sim_free(a);
    coag_kernel_free(k);
}

/* An event-driven sim of `n` monomers (method, sampler, seed; mass 1). */
static coag_sim *eventflow_sim(const coag_kernel *k, const coag_fragmentation *f, int method, int sampler,
                               double truncation, uint64_t seed, size_t n) {
    static double ones[1 << 12];
    for (size_t i = 0; i < n; i++) ones[i] = 1.0;
    coag_eventflow_config c;
    OK(coag_eventflow_default_config(&c, sizeof c));
    c.method = method;
    c.sampler = sampler;
    c.truncation = truncation;
    c.seed = seed;
    coag_sim *s;
    OK(coag_eventflow_new(&c, k, f, ones, n, &s));
    return s;
}

/* Low-rank Monte Carlo over particle sizes (COAG_EVENTFLOW_LOWRANK): the constant-kernel
 * solution from monomers, M0(1) = 2/3 (one comparison at the suite's threshold); what
 * its configuration refuses; a clone and a restored checkpoint continue bit for bit. */
static void lowrank_sizes_scheme(void) {
    coag_kernel *k;
    OK(coag_kernel_new_constant(1.0, &k));
    double e_m0;
    OK(coag_exact_moment(COAG_EXACT_CONSTANT, 0, 1.0, &e_m0));
    stats m0 = {0};
    for (int r = 0; r < REPLICAS; r++) {
        coag_sim *s = eventflow_sim(k, NULL, COAG_EVENTFLOW_LOWRANK, COAG_SAMPLER_DEFAULT, 0.0, 4000 + r, 1 << 12);
        OK(coag_sim_advance_to(s, 1.0, NULL));
        double v;
        OK(coag_sim_moment(s, 0.0, &v));
        stats_push(&m0, v);
        coag_sim_free(s);
    }
    CHECK(fabs(m0.mean - e_m0) < Z_TOL * stats_se(&m0), "lowrank-sizes: M0 %g ± %g vs %g", m0.mean, stats_se(&m0),
          e_m0);
    /* refused settings, and no caller-owned workspace */
    static double sizes[64];
    for (int i = 0; i < 64; i++) sizes[i] = 0.25 + 0.5 * i;
    coag_fragmentation *f;
    OK(coag_fragmentation_new_binary_uniform(0.5, &f));
    coag_eventflow_config c;
    coag_sim *s = NULL;
    for (int v = 0; v < 5; v++) {
        OK(coag_eventflow_default_config(&c, sizeof c));
        c.method = COAG_EVENTFLOW_LOWRANK;
        if (v == 0) c.capacity = 100;
        if (v == 1) c.truncation = 10.0;
        if (v == 2) c.sampler = COAG_SAMPLER_TREE;
        if (v == 3) c.strict_bound = 1;
        EXPECT(coag_eventflow_new(&c, k, v == 4 ? f : NULL, sizes, 64, &s), COAG_INVALID_ARGUMENT);
    }
    OK(coag_eventflow_default_config(&c, sizeof c));
    c.method = COAG_EVENTFLOW_LOWRANK;
    size_t bytes;
    EXPECT(coag_eventflow_workspace_size(&c, NULL, 64, &bytes), COAG_UNSUPPORTED);
    /* checkpoint, restore and clone of a run from continuous sizes */
    c.seed = 5;
    coag_sim *a, *b;
    OK(coag_eventflow_new(&c, k, NULL, sizes, 64, &a));
    OK(coag_eventflow_new(&c, k, NULL, sizes, 64, &b));
    OK(coag_sim_advance_to(a, 0.5, NULL));
    size_t need;
    uint8_t *buf = snapshot(a, &need);
    coag_sim *cl;
    OK(coag_sim_clone(a, &cl));
    OK(coag_sim_restore(b, buf, need));
    OK(coag_sim_advance_to(a, 3.0, NULL));
    OK(coag_sim_advance_to(b, 3.0, NULL));
    OK(coag_sim_advance_to(cl, 3.0, NULL));
    CHECK(same_sizes(a, b), "restored lowrank-sizes run differs");
    CHECK(same_sizes(a, cl), "cloned lowrank-sizes run differs");
    double mass;
    OK(coag_sim_moment(a, 1.0, &mass));
    CHECK(fabs(mass - 1.0) < 1e-12, "lowrank-sizes mass %g", mass);
    free(buf);
    coag_sim_free(a);
    coag_sim_free(b);
    coag_sim_free(cl);
    coag_fragmentation_free(f);
    coag_kernel_free(k);
}

/* The event-driven schemes over particle sizes (Eibeck & Wagner 2000) against the
 * constant-kernel solution from monomers, M0(t) = 1 / (1 + t/2) (per unit of mass: both
 * schemes are given mass 1), with every sampler; the mass flow algorithm's gel mass for
 * the multiplicative kernel, 1 - 1/t at t = 2; configuration, checkpoints and clones. */
static void eventflow_schemes(void) {
    coag_kernel *k;
    OK(coag_kernel_new_constant(1.0, &k));
    enum { NP = 1 << 12 };
    double e_m0;
    OK(coag_exact_moment(COAG_EXACT_CONSTANT, 0, 1.0, &e_m0));
    const int methods[2] = {COAG_EVENTFLOW_MFA, COAG_EVENTFLOW_DSA};
    const int samplers[3] = {COAG_SAMPLER_DEFAULT, COAG_SAMPLER_TREE, COAG_SAMPLER_GROUPS};
    for (int mi = 0; mi < 2; mi++) {
        for (int si = 0; si < 3; si++) {
            stats m0 = {0};
            for (int r = 0; r < REPLICAS; r++) {
                coag_sim *s = eventflow_sim(k, NULL, methods[mi], samplers[si], 0.0, 2000 + r, NP);
                for (int h = 1; h <= 10; h++) OK(coag_sim_advance_to(s, 0.1 * h, NULL));
                double v;
                OK(coag_sim_moment(s, 0.0, &v));
                stats_push(&m0, v);
                coag_sim_free(s);
            }
            CHECK(fabs(m0.mean - e_m0) < Z_TOL * stats_se(&m0), "eventflow %d sampler %d: M0 %g ± %g vs %g",
                  mi, si, m0.mean, stats_se(&m0), e_m0);
        }
        /* the sampler is the one asked for: the default is groups for MFA, the tree for
         * DSA (the same run bit for bit), the other one another run */
        coag_sim *d = eventflow_sim(k, NULL, methods[mi], COAG_SAMPLER_DEFAULT, 0.0, 7, 256);
        coag_sim *g = eventflow_sim(k, NULL, methods[mi], mi == 0 ? COAG_SAMPLER_GROUPS : COAG_SAMPLER_TREE,
                                    0.0, 7, 256);
        coag_sim *o = eventflow_sim(k, NULL, methods[mi], mi == 0 ? COAG_SAMPLER_TREE : COAG_SAMPLER_GROUPS,
                                    0.0, 7, 256);
        OK(coag_sim_advance_to(d, 1.0, NULL));
        OK(coag_sim_advance_to(g, 1.0, NULL));
        OK(coag_sim_advance_to(o, 1.0, NULL));
        CHECK(same_sim(d, g), "method %d: the default sampler is not the documented one", mi);
        CHECK(!same_sizes(d, o), "method %d: the other sampler gave the same run", mi);
        coag_sim_free(d);
        coag_sim_free(g);
        coag_sim_free(o);
    }
    coag_kernel_free(k);

    /* gelation: the mass flow algorithm's gel mass 1 - n(t)/N against 1 - 1/t with
     * b_N = N (one run's sd is 0.008; 400 replicas measured the bias at -0.0002 ± 0.0004,
     * so no allowance beyond the replicas' own: a factor 2 in the rates moves it by
     * tenths) */
    coag_kernel *km;
    OK(coag_kernel_new_multiplicative(&km));
    stats gel = {0};
    for (int r = 0; r < REPLICAS; r++) {
        coag_sim *s = eventflow_sim(km, NULL, COAG_EVENTFLOW_MFA, COAG_SAMPLER_DEFAULT, NP, 3000 + r, NP);
        OK(coag_sim_advance_to(s, 2.0, NULL));
        double g;
        OK(coag_sim_gel_mass(s, &g));
        stats_push(&gel, g);
        coag_sim_free(s);
    }
    CHECK(fabs(gel.mean - 0.5) < Z_TOL * stats_se(&gel), "MFA gel mass %g ± %g vs 0.5", gel.mean, stats_se(&gel));

    /* configuration read back (resolved), checkpoint, restore and clone continue bit for
     * bit: direct simulation with fragmentation */
    coag_fragmentation *f;
    OK(coag_fragmentation_new_binary_uniform(0.5, &f));
    coag_sim *a = eventflow_sim(km, f, COAG_EVENTFLOW_DSA, COAG_SAMPLER_DEFAULT, 0.0, 17, 256);
    coag_sim *b = eventflow_sim(km, f, COAG_EVENTFLOW_DSA, COAG_SAMPLER_DEFAULT, 0.0, 17, 256);
    coag_eventflow_config back;
    OK(coag_sim_eventflow_config(a, &back, sizeof back));
    CHECK(back.method == COAG_EVENTFLOW_DSA && back.capacity == 4 * 256 && back.sampler == COAG_SAMPLER_TREE &&
              back.seed == 17,
          "config read back: method %d capacity %llu sampler %d", back.method, (unsigned long long)back.capacity,
          back.sampler);
    int m;
    EXPECT(coag_sim_method(a, &m), COAG_UNSUPPORTED);
    EXPECT(coag_sim_set_mass(a, 2.0), COAG_UNSUPPORTED);
    OK(coag_sim_advance_to(a, 0.5, NULL));
    size_t need;
    uint8_t *buf = snapshot(a, &need);
    coag_sim *cl;
    OK(coag_sim_clone(a, &cl));
    CHECK(same_sim(a, cl), "DSA clone differs");
    OK(coag_sim_restore(b, buf, need));
    OK(coag_sim_advance_to(a, 1.5, NULL));
    OK(coag_sim_advance_to(b, 1.5, NULL));
    OK(coag_sim_advance_to(cl, 1.5, NULL));
    CHECK(same_sizes(a, b), "restored DSA run differs");
    CHECK(same_sizes(a, cl), "cloned DSA run differs");
    /* a sim of another capacity the state fits takes the checkpoint (a run that filled
     * its workspace moves to a larger one) and keeps its own capacity */
    coag_eventflow_config c;
    OK(coag_eventflow_default_config(&c, sizeof c));
    c.method = COAG_EVENTFLOW_DSA;
    c.capacity = 5000;
    static double ones[256];
    for (int i = 0; i < 256; i++) ones[i] = 1.0;
    coag_sim *other;
    OK(coag_eventflow_new(&c, km, f, ones, 256, &other));
    OK(coag_sim_restore(other, buf, need));
    OK(coag_sim_eventflow_config(other, &back, sizeof back));
    CHECK(back.capacity == 5000, "restored capacity %llu", (unsigned long long)back.capacity);
    coag_sim_free(other);
    /* another configuration refuses the checkpoint, the sim unchanged */
    for (int v = 0; v < 4; v++) {
        OK(coag_eventflow_default_config(&c, sizeof c));
        c.method = COAG_EVENTFLOW_DSA;
        if (v == 0) c.mass = 2.0;
        if (v == 1) c.sampler = COAG_SAMPLER_GROUPS;
        if (v == 2) c.strict_bound = 1;
        if (v == 3) c.method = COAG_EVENTFLOW_MFA;
        OK(coag_eventflow_new(&c, km, f, ones, 256, &other));
        size_t n0;
        uint8_t *before = snapshot(other, &n0);
        EXPECT(coag_sim_restore(other, buf, need), COAG_BAD_CHECKPOINT);
        size_t n1;
        uint8_t *after = snapshot(other, &n1);
        CHECK(n0 == n1 && memcmp(before, after, n0) == 0, "refused restore %d changed the sim", v);
        free(before);
        free(after);
        coag_sim_free(other);
    }
    free(buf);
    coag_sim_free(a);
    coag_sim_free(b);
    coag_sim_free(cl);

    /* the mass flow algorithm with particles gone to the gel and its mass changed:
     * clone and checkpoint continue the same run */
    coag_sim *mfa = eventflow_sim(km, NULL, COAG_EVENTFLOW_MFA, COAG_SAMPLER_DEFAULT, 64, 5, 256);
    OK(coag_sim_advance_to(mfa, 1.5, NULL));
    double g0;
    OK(coag_sim_gel_mass(mfa, &g0));
    CHECK(g0 > 0.0, "no particle left before the clone (gel %g)", g0);
    OK(coag_sim_set_mass(mfa, 3.0));
    OK(coag_sim_eventflow_config(mfa, &back, sizeof back));
    CHECK(back.mass == 3.0 && back.truncation == 64 && back.sampler == COAG_SAMPLER_GROUPS, "MFA config");
    coag_sim *mcl, *mrs = eventflow_sim(km, NULL, COAG_EVENTFLOW_MFA, COAG_SAMPLER_DEFAULT, 64, 99, 256);
    OK(coag_sim_clone(mfa, &mcl));
    CHECK(same_sim(mfa, mcl), "MFA clone differs");
    buf = snapshot(mfa, &need);
    OK(coag_sim_restore(mrs, buf, need));
    free(buf);
    OK(coag_sim_advance_to(mfa, 3.0, NULL));
    OK(coag_sim_advance_to(mcl, 3.0, NULL));
    OK(coag_sim_advance_to(mrs, 3.0, NULL));
    CHECK(same_sim(mfa, mcl) && same_sizes(mfa, mcl), "cloned MFA run differs");
    CHECK(same_sizes(mfa, mrs), "restored MFA run differs");
    coag_sim_free(mfa);
    coag_sim_free(mcl);
    coag_sim_free(mrs);

    /* both schemes in memory the caller owns run bit for bit as in the library's; a
     * workspace too small, misaligned or overlapping the sizes is refused */
    for (int mi = 0; mi < 2; mi++) {
        coag_eventflow_config wc;
        OK(coag_eventflow_default_config(&wc, sizeof wc));
        wc.method = mi == 0 ? COAG_EVENTFLOW_MFA : COAG_EVENTFLOW_DSA;
        wc.truncation = mi == 0 ? 64.0 : 0.0;
        wc.seed = 11;
        size_t bytes;
        OK(coag_eventflow_workspace_size(&wc, f, 256, &bytes));
        double *ws = calloc(bytes / 8 + 1, sizeof *ws);
        coag_sim *own, *in, *none2 = NULL;
        OK(coag_eventflow_new(&wc, km, f, ones, 256, &own));
        EXPECT(coag_eventflow_new_in(&wc, km, f, ones, 256, ws, bytes - 8, &none2), COAG_BUFFER_TOO_SMALL);
        EXPECT(coag_eventflow_new_in(&wc, km, f, ones, 256, (char *)ws + 1, bytes, &none2), COAG_INVALID_ARGUMENT);
        /* sizes inside the workspace: refused before the workspace is zeroed */
        for (int i = 0; i < 8; i++) ws[i] = 1.0;
        EXPECT(coag_eventflow_new_in(&wc, km, f, ws, 8, ws, bytes, &none2), COAG_INVALID_ARGUMENT);
        CHECK(ws[0] == 1.0 && ws[7] == 1.0, "a refused workspace was zeroed");
        /* a workspace sized without fragmentation is too small for it */
        size_t bare_bytes;
        OK(coag_eventflow_workspace_size(&wc, NULL, 256, &bare_bytes));
        if (mi == 1) {
            CHECK(bare_bytes < bytes, "DSA with fragmentation needs more room: %zu vs %zu", bare_bytes, bytes);
            EXPECT(coag_eventflow_new_in(&wc, km, f, ones, 256, ws, bare_bytes, &none2), COAG_BUFFER_TOO_SMALL);
        }
        CHECK(none2 == NULL, "a sim from a refused workspace");
        OK(coag_eventflow_new_in(&wc, km, f, ones, 256, ws, bytes, &in));
        OK(coag_sim_advance_to(own, 1.0, NULL));
        OK(coag_sim_advance_to(in, 1.0, NULL));
        CHECK(same_sim(own, in), "method %d: the workspace run differs", mi);
        /* a clone (in the library's memory) and a checkpoint move between the two */
        coag_sim *wcl;
        OK(coag_sim_clone(in, &wcl));
        CHECK(same_sim(in, wcl), "method %d: clone of a workspace sim differs", mi);
        size_t wn;
        uint8_t *wb = snapshot(own, &wn);
        OK(coag_sim_restore(in, wb, wn));
        free(wb);
        OK(coag_sim_advance_to(own, 2.0, NULL));
        OK(coag_sim_advance_to(in, 2.0, NULL));
        OK(coag_sim_advance_to(wcl, 2.0, NULL));
        CHECK(same_sim(own, in) && same_sim(own, wcl), "method %d: the runs part after a clone", mi);
        coag_sim_free(wcl);
        coag_sim_free(in);
        coag_sim_free(own);
        free(ws);
    }

    /* clones of states a blank of the first particle's size would not fit: direct
     * simulation emptied by the host, direct simulation over counts under a kernel
     * whose bounds start at size 2 */
    coag_sim *dsa = eventflow_sim(km, NULL, COAG_EVENTFLOW_DSA, COAG_SAMPLER_DEFAULT, 0.0, 1, 16);
    OK(coag_sim_set_sizes(dsa, ones, 0));
    OK(coag_sim_clone(dsa, &cl));
    CHECK(same_sim(dsa, cl), "clone of an empty DSA differs");
    coag_sim_free(cl);
    coag_sim_free(dsa);
    coag_kernel *k2;
    OK(coag_kernel_new_additive(2.0, &k2));
    coag_counts_config cc;
    OK(coag_counts_default_config(&cc, sizeof cc));
    cc.method = COAG_METHOD_DSA_COUNTS;
    uint64_t n3[3] = {0, 0, 100};
    coag_sim *dc;
    OK(coag_counts_new(&cc, k2, n3, 3, &dc));
    OK(coag_sim_method(dc, &m));
    CHECK(m == COAG_METHOD_DSA_COUNTS, "method %d", m);
    OK(coag_sim_advance_to(dc, 0.5, NULL));
    OK(coag_sim_clone(dc, &cl));
    CHECK(same_sim(dc, cl), "clone of dsa-counts differs");
    coag_sim_free(cl);
    coag_sim_free(dc);
    coag_kernel_free(k2);

    /* bad input: clear errors, no sim */
    coag_sim *none = NULL;
    OK(coag_eventflow_default_config(&c, sizeof c));
    c.method = 7;
    EXPECT(coag_eventflow_new(&c, km, NULL, ones, 16, &none), COAG_INVALID_ARGUMENT);
    c.method = COAG_EVENTFLOW_MFA;
    c.sampler = 9;
    EXPECT(coag_eventflow_new(&c, km, NULL, ones, 16, &none), COAG_INVALID_ARGUMENT);
    c.sampler = COAG_SAMPLER_DEFAULT;
    c.truncation = -1.0;
    EXPECT(coag_eventflow_new(&c, km, NULL, ones, 16, &none), COAG_INVALID_ARGUMENT);
    c.truncation = 0.5; /* below the largest initial size */
    CHECK(coag_eventflow_new(&c, km, NULL, ones, 16, &none) != COAG_OK, "b_N below a size accepted");
    c.truncation = NAN;
    EXPECT(coag_eventflow_new(&c, km, NULL, ones, 16, &none), COAG_INVALID_ARGUMENT);
    size_t qb;
    EXPECT(coag_eventflow_workspace_size(&c, NULL, 16, &qb), COAG_INVALID_ARGUMENT);
    c.truncation = 0.0;
    c.sampler = 9;
    EXPECT(coag_eventflow_workspace_size(&c, NULL, 16, &qb), COAG_INVALID_ARGUMENT);
    c.sampler = COAG_SAMPLER_DEFAULT;
    c.capacity = 100; /* the mass flow algorithm has none */
    EXPECT(coag_eventflow_new(&c, km, NULL, ones, 16, &none), COAG_INVALID_ARGUMENT);
    c.capacity = 0;
    c.method = COAG_EVENTFLOW_DSA;
    c.truncation = 100.0; /* direct simulation has none */
    EXPECT(coag_eventflow_new(&c, km, NULL, ones, 16, &none), COAG_INVALID_ARGUMENT);
    c.truncation = 0.0;
    c.capacity = UINT64_MAX / 2; /* a workspace past any memory */
    EXPECT(coag_eventflow_new(&c, km, NULL, ones, 16, &none), COAG_CAPACITY);
    c.capacity = 8; /* fewer than the initial particles */
    CHECK(coag_eventflow_new(&c, km, NULL, ones, 16, &none) != COAG_OK, "capacity below N accepted");
    c.capacity = 0;
    c.mass = NAN;
    CHECK(coag_eventflow_new(&c, km, NULL, ones, 16, &none) != COAG_OK, "NaN mass accepted");
    c.mass = 1.0;
    double bad[2] = {1.0, -2.0};
    CHECK(coag_eventflow_new(&c, km, NULL, bad, 2, &none) != COAG_OK, "a negative size accepted");
    /* a user kernel that declares no product majorant */
    static double k1 = 1.0;
    coag_user_kernel bare = {c_const, NULL, 0, NULL, 0, NULL, &k1};
    coag_kernel *nomaj;
    OK(coag_kernel_new_user(&bare, &nomaj));
    EXPECT(coag_eventflow_new(&c, nomaj, NULL, ones, 16, &none), COAG_UNSUPPORTED);
    CHECK(none == NULL, "a sim was made from bad input");
    coag_kernel_free(nomaj);
    coag_kernel_free(km);
    coag_fragmentation_free(f);
}

/* Changing the kernel between steps: K = 1 on [0, 1], K = 2 on [1, 2] gives
 * 1/M0(2) = 1 + 1/2 + 1, i.e. M0 = 0.4 (from M0' = -K M0^2 / 2). */
static void change_kernel_between_steps(void) {
    coag_kernel *k1, *k2;
    OK(coag_kernel_new_constant(1.0, &k1));
    OK(coag_kernel_new_constant(2.0, &k2));
    stats m0 = {0};
    for (int r = 0; r < REPLICAS; r++) {
        coag_counts_config c;
        OK(coag_counts_default_config(&c, sizeof c));
        c.seed = 7 + r;
        uint64_t counts[1] = {1 << 13};
        coag_sim *s;
        OK(coag_counts_new(&c, k1, counts, 1, &s));
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
    coag_kernel *k;
    OK(coag_kernel_new_brownian(&k));
    uint64_t finals[2];
    for (int rep = 0; rep < 2; rep++) {
        coag_counts_config c;
        OK(coag_counts_default_config(&c, sizeof c));
        uint64_t counts[1] = {5000};
        coag_sim *s;
        OK(coag_counts_new(&c, k, counts, 1, &s));
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
    coag_kernel *k;
    OK(coag_kernel_new_free_molecular(1.0, &k));
    coag_counts_config c;
    OK(coag_counts_default_config(&c, sizeof c));
    c.seed = 99;
    uint64_t counts[1] = {20000};
    coag_sim *a, *b;
    OK(coag_counts_new(&c, k, counts, 1, &a));
    OK(coag_counts_new(&c, k, counts, 1, &b));
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
    free(ca);
    free(cb);
    free(buf);
    coag_sim_free(a);
    coag_sim_free(b);
    coag_kernel_free(k);

    /* the same for RQMC mass flow, whose randomisation must match */
    coag_kernel *kc;
    coag_fragmentation *f;
    OK(coag_kernel_new_constant(1.0, &kc));
    OK(coag_fragmentation_new_binary_uniform(1.0, &f));
    coag_massflow_config mc;
    OK(coag_massflow_default_config(&mc, sizeof mc));
    mc.randomization = COAG_RANDOMIZATION_OWEN;
    mc.seed = 5;
    double init[1024];
    for (int i = 0; i < 1024; i++) init[i] = 1.0;
    OK(coag_massflow_new(&mc, kc, f, init, 1024, &a));
    OK(coag_massflow_new(&mc, kc, f, init, 1024, &b));
    OK(coag_sim_advance_to(a, 0.3, NULL));
    OK(coag_sim_checkpoint_size(a, &need));
    buf = malloc(need);
    OK(coag_sim_checkpoint(a, buf, need, NULL));
    OK(coag_sim_advance_to(a, 0.8, NULL));
    OK(coag_sim_restore(b, buf, need));
    OK(coag_sim_advance_to(b, 0.8, NULL));
    double xa[1024], xb[1024];
    OK(coag_sim_get_sizes(a, xa, 1024));
    OK(coag_sim_get_sizes(b, xb, 1024));
    CHECK(memcmp(xa, xb, sizeof xa) == 0, "restored mass-flow run differs");
    /* another randomisation refuses the checkpoint */
    coag_sim *other;
    mc.seed = 6;
    OK(coag_massflow_new(&mc, kc, f, init, 1024, &other));
    EXPECT(coag_sim_restore(other, buf, need), COAG_BAD_CHECKPOINT);
    coag_sim_free(other);
    free(buf);
    coag_sim_free(a);
    coag_sim_free(b);
    coag_kernel_free(kc);
    coag_fragmentation_free(f);
}

/* A host applying nucleation between steps: 1000 monomers added at t = 1. */
static void host_modifies_state(void) {
    coag_kernel *k;
    OK(coag_kernel_new_constant(1.0, &k));
    coag_counts_config c;
    OK(coag_counts_default_config(&c, sizeof c));
    uint64_t counts[1] = {10000};
    coag_sim *s;
    OK(coag_counts_new(&c, k, counts, 1, &s));
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
 * allocates its own, and a too small or misaligned workspace is refused. */
static void massflow_in_caller_workspace(void) {
    enum { NP = 1024 };
    coag_kernel *k;
    coag_fragmentation *f;
    OK(coag_kernel_new_constant(1.0, &k));
    OK(coag_fragmentation_new_binary_uniform(1.0, &f));
    coag_massflow_config c;
    OK(coag_massflow_default_config(&c, sizeof c));
    c.randomization = COAG_RANDOMIZATION_OWEN;
    c.seed = 17;
    double sizes[NP];
    for (int i = 0; i < NP; i++) sizes[i] = 1.0;
    size_t bytes = 0;
    OK(coag_massflow_workspace_size(NP, &bytes));
    CHECK(bytes == 6 * NP * sizeof(double), "workspace %zu bytes", bytes);
    double *ws = malloc(bytes);
    coag_sim *own, *in;
    OK(coag_massflow_new(&c, k, f, sizes, NP, &own));
    EXPECT(coag_massflow_new_in(&c, k, f, sizes, NP, ws, bytes - 8, &in), COAG_BUFFER_TOO_SMALL);
    EXPECT(coag_massflow_new_in(&c, k, f, sizes, NP, (char *)ws + 4, bytes - 8, &in), COAG_INVALID_ARGUMENT);
    EXPECT(coag_massflow_new_in(&c, k, f, sizes, NP, NULL, bytes, &in), COAG_NULL_PARAMETER);
    EXPECT(coag_massflow_new_in(&c, k, f, ws, NP, ws, bytes, &in), COAG_INVALID_ARGUMENT); /* overlap */
    {
        /* a refused set-up leaves the caller's workspace as it was */
        for (size_t i = 0; i < bytes / sizeof(double); i++) ws[i] = 7.0;
        coag_massflow_config bad = c;
        bad.dt = -1.0;
        EXPECT(coag_massflow_new_in(&bad, k, f, sizes, NP, ws, bytes, &in), COAG_INVALID_ARGUMENT);
        CHECK(ws[0] == 7.0 && ws[bytes / sizeof(double) - 1] == 7.0, "workspace untouched by a refused call");
    }
    OK(coag_massflow_new_in(&c, k, f, sizes, NP, ws, bytes, &in));
    for (int h = 1; h <= 30; h++) {
        OK(coag_sim_advance_to(own, 0.05 * h, NULL));
        OK(coag_sim_advance_to(in, 0.05 * h, NULL));
    }
    double a[NP], b[NP];
    OK(coag_sim_get_sizes(own, a, NP));
    OK(coag_sim_get_sizes(in, b, NP));
    CHECK(memcmp(a, b, sizeof a) == 0, "caller workspace run differs");
    double m2;
    OK(coag_sim_moment(in, 2.0, &m2));
    CHECK(m2 > 1.0 && m2 < 3.0, "M2 %g", m2);
    coag_sim_free(in);
    coag_sim_free(own);
    free(ws);
    coag_kernel_free(k);
    coag_fragmentation_free(f);
}

int main(void) {
    printf("libcoagula %s\n", coag_version());
    massflow_in_caller_workspace();
    massflow_lecot();
    counts_schemes();
    bucket_engines();
    eventflow_schemes();
    lowrank_sizes_scheme();
    change_kernel_between_steps();
    host_randomness();
    checkpoint_restore();
    host_modifies_state();
    return finish("test_schemes");
}
