/* Drives every scheme step by step through the C ABI against exact solutions.
 * Statistical checks use R independent replicas and a tolerance of Z_TOL standard errors
 * (a wrong factor 2 in a rate moves the means by tens of standard errors). */
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
static double c_const_sup(double lo, double hi, void *ud) {
    (void)lo;
    (void)hi;
    return *(const double *)ud;
}

static void counts_schemes(void) {
    static double k0 = 1.0;
    coag_user_kernel uk = {c_const, NULL, 1, c_const_factors, 1, c_const_sup, &k0};
    coag_kernel *user, *builtin;
    OK(coag_kernel_new_user(&uk, &user));
    OK(coag_kernel_new_constant(1.0, &builtin));
    const coag_kernel *kernels[2] = {builtin, user};
    const int methods[4] = {COAG_METHOD_LOWRANK, COAG_METHOD_LOWRANK_TREE, COAG_METHOD_INVERSE,
                            COAG_METHOD_REJECTION};
    double e_m0, e_n1;
    OK(coag_exact_moment(COAG_EXACT_CONSTANT, 0, 2.0, &e_m0));
    OK(coag_exact_density(COAG_EXACT_CONSTANT, 1, 2.0, &e_n1));
    for (int ki = 0; ki < 2; ki++) {
        for (int mi = 0; mi < 4; mi++) {
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
    change_kernel_between_steps();
    host_randomness();
    checkpoint_restore();
    host_modifies_state();
    return finish("test_schemes");
}
