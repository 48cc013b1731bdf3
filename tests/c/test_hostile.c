/* The C ABI under hostile use (issue 14): corrupted, crafted and foreign checkpoints,
 * bounded and cancelled calls, the reproducers of the issue (each must return a
 * status), a stuck random callback, host splits of time, and the coupling calls (set
 * time and mass, read the configuration, clone). Built with -fsanitize=address,undefined
 * and run under valgrind in CI. */
#include <stdint.h>
#include <string.h>

#include <time.h>

#include "check.h"

/* The checkpoint checksum (core/src/checkpoint.rs), to reseal a crafted checkpoint. */
static uint64_t ckpt_checksum(const uint8_t *b, size_t n) {
    const uint64_t k = 0x9e3779b97f4a7c15ULL;
    uint64_t h = 0x436f6167756c6121ULL;
    for (size_t i = 0; i < n; i += 8) {
        uint64_t w = 0;
        size_t m = n - i < 8 ? n - i : 8;
        for (size_t j = 0; j < m; j++) w |= (uint64_t)b[i + j] << (8 * j);
        h = (h ^ w) * k;
        h ^= h >> 29;
    }
    h ^= (uint64_t)n;
    h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ULL;
    h = (h ^ (h >> 27)) * 0x94d049bb133111ebULL;
    return h ^ (h >> 31);
}

static void reseal(uint8_t *b, size_t n) {
    uint64_t s = ckpt_checksum(b, n - 8);
    for (int j = 0; j < 8; j++) b[n - 8 + j] = (uint8_t)(s >> (8 * j));
}

static uint64_t rng_state = 0x853c49e6748fea9bULL;
static uint64_t next_rand(void) {
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return rng_state;
}

/* A checkpoint of `s` (malloc'ed; length in *n). */
static uint8_t *checkpoint(coag_sim *s, size_t *n) {
    OK(coag_sim_checkpoint_size(s, n));
    uint8_t *b = malloc(*n);
    OK(coag_sim_checkpoint(s, b, *n, NULL));
    return b;
}

/* Whether two sims hold the same checkpoint (state, stream, configuration). */
static int same(coag_sim *a, coag_sim *b) {
    size_t na, nb;
    uint8_t *x = checkpoint(a, &na), *y = checkpoint(b, &nb);
    int eq = na == nb && memcmp(x, y, na) == 0;
    free(x);
    free(y);
    return eq;
}

enum { MASSFLOW = -1, EVENT_MFA = -2, EVENT_DSA = -3 };

/* A sim of `method` (a COAG_METHOD_*, MASSFLOW or EVENT_*) under kernel k from a small
 * polydisperse start, with the defaults otherwise. */
static coag_sim *make(int method, coag_kernel *k, double volume_or_dt) {
    coag_sim *s = NULL;
    if (method == EVENT_MFA || method == EVENT_DSA) {
        coag_eventflow_config c;
        OK(coag_eventflow_default_config(&c, sizeof c));
        c.method = method == EVENT_MFA ? COAG_EVENTFLOW_MFA : COAG_EVENTFLOW_DSA;
        double x[64];
        for (int i = 0; i < 64; i++) x[i] = 1.0 + i % 5;
        OK(coag_eventflow_new(&c, k, NULL, x, 64, &s));
    } else if (method == MASSFLOW) {
        coag_massflow_config c;
        OK(coag_massflow_default_config(&c, sizeof c));
        c.dt = volume_or_dt > 0 ? volume_or_dt : 0.05;
        double x[64];
        for (int i = 0; i < 64; i++) x[i] = 1.0 + i % 5;
        OK(coag_massflow_new(&c, k, NULL, x, 64, &s));
    } else {
        coag_counts_config c;
        OK(coag_counts_default_config(&c, sizeof c));
        c.method = method;
        c.volume = volume_or_dt;
        /* growing size tables stop at 8 MiB (COAG_CAPACITY) instead of half the
         * machine's memory: the runaway cases end in milliseconds */
        c.memory_budget = 8u << 20;
        uint64_t n[4] = {3000, 40, 0, 7};
        OK(coag_counts_new(&c, k, n, 4, &s));
    }
    return s;
}

/* COAG_TEST_QUICK set (the valgrind run): smaller work limits and fewer crafted
 * checkpoints, the same checks. */
static int quick = 0;

static const int methods[] = {MASSFLOW,
                              COAG_METHOD_LOWRANK,
                              COAG_METHOD_LOWRANK_TREE,
                              COAG_METHOD_INVERSE,
                              COAG_METHOD_REJECTION,
                              COAG_METHOD_DSA_COUNTS,
                              EVENT_MFA,
                              EVENT_DSA};
enum { NMETHODS = sizeof methods / sizeof methods[0] };

/* Every flipped bit of a checkpoint is refused, and the sim stays as it was. */
static void corrupted_checkpoints(coag_kernel *k) {
    for (int m = 0; m < NMETHODS; m++) {
        coag_sim *s = make(methods[m], k, 0.0);
        OK(coag_sim_advance_to(s, 0.5, NULL));
        size_t n;
        uint8_t *b = checkpoint(s, &n);
        int refused = 0, tried = 0;
        /* every byte of a small checkpoint, ~1500 spread over a large one */
        size_t stride = n / 1500 + 1;
        for (size_t i = 0; i < n; i += (i < 256 ? 1 : stride)) {
            b[i] ^= (uint8_t)(1u << (i % 8));
            refused += coag_sim_restore(s, b, n) == COAG_BAD_CHECKPOINT;
            tried++;
            b[i] ^= (uint8_t)(1u << (i % 8));
        }
        CHECK(refused == tried, "method %d: %d of %d flipped bits refused", methods[m], refused,
              tried);
        /* truncated, extended */
        EXPECT(coag_sim_restore(s, b, n - 1), COAG_BAD_CHECKPOINT);
        EXPECT(coag_sim_restore(s, b, 8), COAG_BAD_CHECKPOINT);
        size_t n2;
        uint8_t *b2 = checkpoint(s, &n2);
        CHECK(n2 == n && memcmp(b, b2, n) == 0, "method %d: sim changed by refused restores",
              methods[m]);
        free(b2);
        free(b);
        coag_sim_free(s);
    }
}

/* Crafted checkpoints (random words changed, then resealed with the right checksum):
 * an accepted one is a valid state — observables finite, a bounded advance returns a
 * status and lands on its target or stops by its limit. Returns the accepted count. */
static void crafted_checkpoints(coag_kernel *k, int rounds) {
    static const uint64_t specials[] = {
        0, 1, 2, 0x7ff8000000000000ULL /* NaN */, 0x7ff0000000000000ULL /* inf */,
        0xfff0000000000000ULL /* -inf */, 0xbff0000000000000ULL /* -1.0 */,
        0x3ff0000000000000ULL /* 1.0 */, 1ULL /* denormal */, UINT64_MAX, 1ULL << 63,
        1ULL << 32, 0x7fefffffffffffffULL /* DBL_MAX */};
    for (int m = 0; m < NMETHODS; m++) {
        coag_sim *s = make(methods[m], k, 0.0);
        OK(coag_sim_advance_to(s, 0.5, NULL));
        size_t n;
        uint8_t *b = checkpoint(s, &n);
        uint8_t *c = malloc(n);
        int accepted = 0, bad_status = 0, bad_values = 0;
        for (int round = 0; round < rounds; round++) {
            memcpy(c, b, n);
            int words = 1 + (int)(next_rand() % 3);
            for (int w = 0; w < words; w++) {
                size_t at = 8 * (size_t)(next_rand() % ((n - 8) / 8));
                uint64_t v;
                switch (next_rand() % 4) {
                case 0: v = specials[next_rand() % (sizeof specials / sizeof specials[0])]; break;
                case 1: memcpy(&v, c + at, 8); v ^= 1ULL << (next_rand() % 64); break;
                case 2: v = next_rand() % 100; break;
                default: v = next_rand(); break;
                }
                memcpy(c + at, &v, 8);
            }
            reseal(c, n);
            coag_sim *t = NULL;
            OK(coag_sim_clone(s, &t));
            int st = coag_sim_restore(t, c, n);
            if (st == COAG_OK) {
                accepted++;
                double tm = -1, m0 = -1, m1 = -1;
                OK(coag_sim_time(t, &tm));
                /* a moment may overflow a double (a restored volume of 1e-300 is as
                 * valid as a constructed one): COAG_CAPACITY, never a wrong number */
                int s0 = coag_sim_moment(t, 0.0, &m0), s1 = coag_sim_moment(t, 1.0, &m1);
                if (!(isfinite(tm) && tm >= 0 && (s0 == COAG_CAPACITY || (s0 == COAG_OK && isfinite(m0) && m0 >= 0)) &&
                      (s1 == COAG_CAPACITY || (s1 == COAG_OK && isfinite(m1) && m1 >= 0)))) {
                    bad_values++;
                    fprintf(stderr, "  invalid state: t %g M0 %g (%s) M1 %g (%s)\n", tm, m0,
                            coag_status_name(s0), m1, coag_status_name(s1));
                }
                OK(coag_sim_set_work_limit(t, 200000));
                int a = coag_sim_advance_to(t, tm + 0.5, NULL);
                if (a == COAG_PANIC || a == COAG_NULL_PARAMETER || a == COAG_BAD_CHECKPOINT)
                    bad_status++;
                double t2 = -1;
                OK(coag_sim_time(t, &t2));
                if (a == COAG_OK && t2 != tm + 0.5) bad_status++;
            } else if (st != COAG_BAD_CHECKPOINT && st != COAG_CAPACITY) {
                bad_status++;
            }
            coag_sim_free(t);
        }
        CHECK(bad_status == 0 && bad_values == 0,
              "method %d: %d bad statuses, %d invalid accepted states (%d accepted)", methods[m],
              bad_status, bad_values, accepted);
        printf("  crafted checkpoints, method %d: %d of %d accepted, all valid\n", methods[m],
               accepted, rounds);
        free(c);
        free(b);
        coag_sim_free(s);
    }
}

/* A checkpoint restores only into a sim configured the same way. */
static void foreign_checkpoints(void) {
    coag_kernel *k1, *k2;
    OK(coag_kernel_new_constant(1.0, &k1));
    OK(coag_kernel_new_constant(2.0, &k2));
    coag_sim *a = make(COAG_METHOD_LOWRANK, k1, 0.0);
    OK(coag_sim_advance_to(a, 0.3, NULL));
    size_t n;
    uint8_t *b = checkpoint(a, &n);
    coag_sim *other = make(COAG_METHOD_LOWRANK, k1, 2.0); /* another volume */
    EXPECT(coag_sim_restore(other, b, n), COAG_BAD_CHECKPOINT);
    coag_sim_free(other);
    other = make(COAG_METHOD_LOWRANK, k2, 0.0); /* another kernel parameter */
    EXPECT(coag_sim_restore(other, b, n), COAG_BAD_CHECKPOINT);
    coag_sim_free(other);
    other = make(COAG_METHOD_INVERSE, k1, 0.0); /* another method */
    EXPECT(coag_sim_restore(other, b, n), COAG_BAD_CHECKPOINT);
    coag_sim_free(other);
    coag_counts_config c;
    OK(coag_counts_default_config(&c, sizeof c));
    c.size_limit = 1000; /* another size limit */
    uint64_t n0[4] = {3000, 40, 0, 7};
    OK(coag_counts_new(&c, k1, n0, 4, &other));
    EXPECT(coag_sim_restore(other, b, n), COAG_BAD_CHECKPOINT);
    coag_sim_free(other);
    c.size_limit = 0;
    c.memory_budget = 8u << 20;
    c.seed = 99; /* another seed: the stream is restored, fine */
    OK(coag_counts_new(&c, k1, n0, 4, &other));
    OK(coag_sim_restore(other, b, n));
    CHECK(same(a, other), "restored into a sim of another seed");
    coag_sim_free(other);
    free(b);
    coag_sim_free(a);

    a = make(MASSFLOW, k1, 0.05);
    OK(coag_sim_advance_to(a, 0.3, NULL));
    b = checkpoint(a, &n);
    other = make(MASSFLOW, k1, 0.02); /* another dt */
    EXPECT(coag_sim_restore(other, b, n), COAG_BAD_CHECKPOINT);
    coag_sim_free(other);
    coag_massflow_config mc;
    OK(coag_massflow_default_config(&mc, sizeof mc));
    mc.dt = 0.05;
    mc.mass = 3.0; /* another mass */
    double x[64];
    for (int i = 0; i < 64; i++) x[i] = 1.0 + i % 5;
    OK(coag_massflow_new(&mc, k1, NULL, x, 64, &other));
    EXPECT(coag_sim_restore(other, b, n), COAG_BAD_CHECKPOINT);
    char msg[256];
    coag_last_error_message(msg, sizeof msg, NULL);
    CHECK(strstr(msg, "mass") != NULL, "the message names the field: %s", msg);
    coag_sim_free(other);
    free(b);
    coag_sim_free(a);
    coag_kernel_free(k1);
    coag_kernel_free(k2);
}

/* A work limit interrupts; calling again continues the same run, bit for bit. The
 * default clock keeps the next proposal: host stops do not change the run. */
static void bounded_and_split_calls(coag_kernel *k) {
    for (int m = 0; m < NMETHODS; m++) {
        coag_sim *a = make(methods[m], k, 0.0), *b = make(methods[m], k, 0.0),
                 *c = make(methods[m], k, 0.0);
        OK(coag_sim_advance_to(a, 2.0, NULL));
        /* (the event-driven sims of 64 particles make a few hundred proposals) */
        OK(coag_sim_set_work_limit(b, methods[m] == MASSFLOW ? 64 : methods[m] < 0 ? 5 : 500));
        int interrupted = 0, st;
        coag_step_report r;
        OK(coag_step_report_init(&r, sizeof r));
        while ((st = coag_sim_advance_to(b, 2.0, &r)) == COAG_INTERRUPTED) {
            interrupted++;
            double tb;
            OK(coag_sim_time(b, &tb));
            CHECK(tb == r.time && tb < 2.0, "interrupted at %g", tb);
            if (interrupted > 100000) break;
        }
        EXPECT(st, COAG_OK);
        CHECK(interrupted >= 3, "method %d: %d interruptions", methods[m], interrupted);
        OK(coag_sim_set_work_limit(b, 0));
        /* split by the host */
        OK(coag_sim_advance_to(c, 0.7, NULL));
        OK(coag_sim_advance_to(c, 1.3, NULL));
        OK(coag_sim_advance_to(c, 1.3, NULL));
        OK(coag_sim_advance_to(c, 2.0, NULL));
        CHECK(same(a, b), "method %d: interrupted run differs", methods[m]);
        CHECK(same(a, c), "method %d: split run differs", methods[m]);
        coag_sim_free(a);
        coag_sim_free(b);
        coag_sim_free(c);
    }
}

static int polls = 0;
static int cancel_after_two(void *ud) {
    (void)ud;
    return ++polls >= 2;
}

static uint64_t stuck(void *ud) {
    (void)ud;
    return 0x0123456789abcdefULL;
}

/* The reproducers: each returns a status. */
static void reproducers(coag_kernel *k) {
    clock_t c0 = clock();
#define LAP(name) printf("    %s: %.1f s\n", name, (double)(clock() - c0) / CLOCKS_PER_SEC)
    /* advance_to(1e300) with a work limit */
    coag_sim *s = make(MASSFLOW, k, 0.01);
    OK(coag_sim_set_work_limit(s, quick ? 20000 : 1000000));
    EXPECT(coag_sim_advance_to(s, 1e300, NULL), COAG_INTERRUPTED);
    coag_sim_free(s);
    s = make(COAG_METHOD_LOWRANK, k, 0.0);
    OK(coag_sim_set_work_limit(s, quick ? 20000 : 1000000));
    int st = coag_sim_advance_to(s, 1e300, NULL);
    CHECK(st == COAG_INTERRUPTED || st == COAG_CAPACITY, "1e300: %s", coag_status_name(st));
    coag_sim_free(s);
    LAP("1e300");
    /* a cancellation callback, polled before every mass-flow step */
    s = make(MASSFLOW, k, 0.01);
    polls = 0;
    OK(coag_sim_set_cancel_callback(s, cancel_after_two, NULL));
    EXPECT(coag_sim_advance_to(s, 1e300, NULL), COAG_INTERRUPTED);
    CHECK(polls == 2, "polled %d times", polls);
    OK(coag_sim_set_cancel_callback(s, NULL, NULL));
    coag_sim_free(s);
    LAP("cancel");
    /* set_dt(1e-300): a step below the clock's resolution */
    s = make(MASSFLOW, k, 0.05);
    OK(coag_sim_advance_to(s, 0.5, NULL));
    OK(coag_sim_set_dt(s, 1e-300));
    EXPECT(coag_sim_advance_to(s, 1.0, NULL), COAG_INVALID_ARGUMENT);
    double t;
    OK(coag_sim_time(s, &t));
    CHECK(t == 0.5, "time %g", t);
    coag_sim_free(s);
    LAP("dt");
    /* volumes of 5e-324 and DBL_MIN: infinite rates */
    for (int m = 1; m < NMETHODS; m++) {
        if (methods[m] < 0) continue; /* size-count sims only */
        double vols[2] = {5e-324, 2.2250738585072014e-308};
        for (int v = 0; v < 2; v++) {
            s = make(methods[m], k, vols[v]);
            /* observables that overflow a double are COAG_CAPACITY, never inf */
            double obs;
            EXPECT(coag_sim_moment(s, 0.0, &obs), COAG_CAPACITY);
            EXPECT(coag_sim_concentration(s, -1.0, INFINITY, &obs), COAG_CAPACITY);
            EXPECT(coag_sim_gel_mass(s, &obs), COAG_CAPACITY);
            st = coag_sim_advance_to(s, 1.0, NULL);
            CHECK(st == COAG_INVALID_RATE || st == COAG_CAPACITY, "method %d volume %g: %s",
                  methods[m], vols[v], coag_status_name(st));
            coag_sim_free(s);
        }
    }
    LAP("volumes");
    /* K0 = 1e300 */
    coag_kernel *huge;
    OK(coag_kernel_new_constant(1e300, &huge));
    for (int m = 0; m < NMETHODS; m++) {
        s = make(methods[m], huge, 0.0);
        OK(coag_sim_set_work_limit(s, quick ? 20000 : 10000000));
        st = coag_sim_advance_to(s, 1.0, NULL);
        CHECK(st == COAG_INVALID_RATE || st == COAG_CAPACITY || st == COAG_INTERRUPTED ||
                  /* (without particle doubling, direct simulation and the mass flow
                   * algorithm merge all their particles in tiny waiting times) */
                  ((methods[m] < 0 || methods[m] == COAG_METHOD_DSA_COUNTS) && st == COAG_OK),
              "method %d K0 = 1e300: %s", methods[m], coag_status_name(st));
        coag_sim_free(s);
    }
    coag_kernel_free(huge);
    LAP("k0");
    /* a host random callback stuck on one word: reported, the call undone */
    for (int m = 0; m < NMETHODS; m++) {
        if (methods[m] == MASSFLOW) {
            /* Monte Carlo points: the QMC default draws no random numbers at all */
            coag_massflow_config mc;
            OK(coag_massflow_default_config(&mc, sizeof mc));
            mc.points = COAG_POINTS_MONTE_CARLO;
            double x[64];
            for (int i = 0; i < 64; i++) x[i] = 1.0 + i % 5;
            OK(coag_massflow_new(&mc, k, NULL, x, 64, &s));
        } else {
            s = make(methods[m], k, 0.0);
        }
        OK(coag_sim_advance_to(s, 0.2, NULL));
        size_t n;
        uint8_t *b = checkpoint(s, &n);
        OK(coag_sim_set_rng_callback(s, stuck, NULL));
        EXPECT(coag_sim_advance_to(s, 5.0, NULL), COAG_RNG_FAILURE);
        OK(coag_sim_set_rng_callback(s, NULL, NULL));
        size_t n2;
        uint8_t *b2 = checkpoint(s, &n2);
        CHECK(n == n2 && memcmp(b, b2, n) == 0, "method %d: stuck stream changed the sim",
              methods[m]);
        free(b);
        free(b2);
        coag_sim_free(s);
    }
    LAP("stuck");
    /* extreme counts, refused up front */
    coag_counts_config c;
    OK(coag_counts_default_config(&c, sizeof c));
    uint64_t big[2] = {UINT64_MAX, 2}; /* more than 2^64 - 1 particles */
    s = NULL;
    EXPECT(coag_counts_new(&c, k, big, 2, &s), COAG_CAPACITY);
    uint64_t heavy[3] = {1, 0, UINT64_MAX / 2}; /* total mass past 2^64 */
    EXPECT(coag_counts_new(&c, k, heavy, 3, &s), COAG_CAPACITY);
    c.method = COAG_METHOD_REJECTION;
    uint64_t many[1] = {1ULL << 36}; /* 512 GB of particle list */
    EXPECT(coag_counts_new(&c, k, many, 1, &s), COAG_CAPACITY);
    c.method = COAG_METHOD_LOWRANK;
    c.size_limit = 3; /* below a size present */
    uint64_t n4[4] = {10, 0, 0, 1};
    EXPECT(coag_counts_new(&c, k, n4, 4, &s), COAG_CAPACITY);
    CHECK(s == NULL, "no sim on error");
}

/* set_time, set_mass, the configuration read back, clones. */
static void coupling(coag_kernel *k) {
    coag_sim *s = make(MASSFLOW, k, 0.05);
    OK(coag_sim_advance_to(s, 0.5, NULL));
    double m1, m1b;
    OK(coag_sim_moment(s, 1.0, &m1));
    OK(coag_sim_set_mass(s, 2.0));
    OK(coag_sim_moment(s, 1.0, &m1b));
    CHECK(fabs(m1b - 2.0 * m1) <= 1e-12 * m1b, "M1 %g -> %g after doubling the mass", m1, m1b);
    EXPECT(coag_sim_set_mass(s, -1.0), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_mass(s, NAN), COAG_INVALID_ARGUMENT);
    coag_massflow_config mc;
    OK(coag_sim_massflow_config(s, &mc, sizeof mc));
    CHECK(mc.mass == 2.0 && mc.dt == 0.05, "config read back: mass %g dt %g", mc.mass, mc.dt);
    coag_counts_config cc;
    EXPECT(coag_sim_counts_config(s, &cc, sizeof cc), COAG_UNSUPPORTED);
    OK(coag_sim_set_time(s, 10.0));
    double t;
    OK(coag_sim_time(s, &t));
    CHECK(t == 10.0, "time %g", t);
    EXPECT(coag_sim_set_time(s, -1.0), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_time(s, INFINITY), COAG_INVALID_ARGUMENT);
    coag_sim *c = NULL;
    OK(coag_sim_clone(s, &c));
    CHECK(same(s, c), "clone differs");
    OK(coag_sim_advance_to(s, 11.0, NULL));
    OK(coag_sim_advance_to(c, 11.0, NULL));
    CHECK(same(s, c), "clone continues differently");
    coag_sim_free(c);
    coag_sim_free(s);

    for (int m = 1; m < NMETHODS; m++) {
        if (methods[m] < 0) continue; /* size-count sims only */
        s = make(methods[m], k, 0.0);
        EXPECT(coag_sim_set_mass(s, 2.0), COAG_UNSUPPORTED);
        OK(coag_sim_counts_config(s, &cc, sizeof cc));
        CHECK(cc.method == methods[m] && cc.volume == 3047.0 && cc.size_limit == (1ULL << 32),
              "method %d config: %d %g %llu", methods[m], cc.method, cc.volume,
              (unsigned long long)cc.size_limit);
        OK(coag_sim_advance_to(s, 0.4, NULL));
        OK(coag_sim_clone(s, &c));
        OK(coag_sim_advance_to(s, 1.0, NULL));
        OK(coag_sim_advance_to(c, 1.0, NULL));
        CHECK(same(s, c), "method %d: clone continues differently", methods[m]);
        OK(coag_sim_set_time(c, 0.0));
        OK(coag_sim_advance_to(c, 0.5, NULL));
        OK(coag_sim_time(c, &t));
        CHECK(t == 0.5, "time after set_time: %g", t);
        coag_sim_free(c);
        coag_sim_free(s);
    }
}

/* Sparse state: a state whose sizes are huge and few is read as (size, count) pairs
 * with nothing dense allocated; empty systems are valid and can be refilled. */
static void sparse_and_empty(void) {
    coag_kernel *k1;
    OK(coag_kernel_new_constant(1.0, &k1));
    /* the case: acceptance-rejection from 1000 monomers to t = 1e9 */
    coag_counts_config c;
    OK(coag_counts_default_config(&c, sizeof c));
    c.method = COAG_METHOD_REJECTION;
    coag_sim *s;
    uint64_t n0[1] = {1000};
    OK(coag_counts_new(&c, k1, n0, 1, &s));
    OK(coag_sim_advance_to(s, 1e9, NULL));
    size_t len = 0, occ = 0, written = 0;
    OK(coag_sim_state_len(s, &len));
    OK(coag_sim_occupied(s, &occ));
    CHECK(len > 100000000 && occ > 0 && occ <= 1000, "state_len %zu, occupied %zu", len, occ);
    uint64_t *sz = malloc(occ * sizeof *sz), *ct = malloc(occ * sizeof *ct);
    double v = 0, m1 = 0;
    EXPECT(coag_sim_get_pairs(s, sz, ct, occ - 1, &v, &written), COAG_BUFFER_TOO_SMALL);
    OK(coag_sim_get_pairs(s, sz, ct, occ, &v, &written));
    uint64_t particles = 0, np = 0;
    double mass = 0;
    for (size_t i = 0; i < written; i++) {
        CHECK(i == 0 || sz[i] > sz[i - 1], "pairs ascending");
        np += ct[i];
        mass += (double)sz[i] * (double)ct[i];
    }
    OK(coag_sim_particle_count(s, &particles));
    OK(coag_sim_moment(s, 1.0, &m1));
    CHECK(written == occ && np == particles, "pairs: %zu of %zu, %llu particles", written, occ,
          (unsigned long long)np);
    CHECK(fabs(mass / v - m1) <= 1e-12 * m1, "mass from pairs %g vs M1 %g", mass / v, m1);
    /* the pairs written back give the same state */
    coag_sim *t2 = NULL;
    OK(coag_sim_clone(s, &t2));
    OK(coag_sim_set_pairs(t2, sz, ct, written, v));
    double m1b = 0;
    OK(coag_sim_moment(t2, 1.0, &m1b));
    CHECK(fabs(m1b - m1) <= 1e-12 * m1, "set_pairs round trip: M1 %.17g vs %.17g", m1b, m1);
    uint64_t dup_s[2] = {3, 3}, dup_c[2] = {1, 1};
    EXPECT(coag_sim_set_pairs(t2, dup_s, dup_c, 2, 1.0), COAG_INVALID_ARGUMENT);
    uint64_t far_s[1] = {1ULL << 40}, far_c[1] = {1};
    EXPECT(coag_sim_set_pairs(t2, far_s, far_c, 1, 1.0), COAG_CAPACITY);
    coag_sim_free(t2);
    free(sz);
    free(ct);
    coag_sim_free(s);
    /* the other case: low-rank from 1000 monomers to t = 1e7 (about 800
     * particles, sizes up to ~1e7): observables without a count vector */
    c.method = COAG_METHOD_LOWRANK;
    OK(coag_counts_new(&c, k1, n0, 1, &s));
    OK(coag_sim_advance_to(s, 1e7, NULL));
    OK(coag_sim_state_len(s, &len));
    OK(coag_sim_occupied(s, &occ));
    OK(coag_sim_moment(s, 1.0, &m1));
    OK(coag_sim_particle_count(s, &particles));
    double gel = 0;
    OK(coag_sim_gel_mass(s, &gel));
    CHECK(len > 1000000 && occ <= particles && particles <= 1000 && fabs(m1 - 1.0) < 1e-12 && gel > 0,
          "low-rank at 1e7: len %zu occupied %zu particles %llu M1 %g", len, occ,
          (unsigned long long)particles, m1);
    coag_sim_free(s);
    /* empty systems, drained and refilled */
    for (int m = 1; m < NMETHODS; m++) {
        if (methods[m] < 0) continue; /* size-count sims only */
        c.method = methods[m];
        uint64_t none[3] = {0, 0, 0};
        c.volume = 10.0;
        OK(coag_counts_new(&c, k1, none, 3, &s));
        OK(coag_sim_advance_to(s, 1.0, NULL));
        OK(coag_sim_particle_count(s, &particles));
        OK(coag_sim_occupied(s, &occ));
        OK(coag_sim_state_len(s, &len));
        double m0 = -1;
        OK(coag_sim_moment(s, 0.0, &m0));
        CHECK(particles == 0 && occ == 0 && len == 0 && m0 == 0.0, "method %d: empty", methods[m]);
        uint64_t ps[2] = {1, 5}, pc[2] = {400, 3};
        OK(coag_sim_set_pairs(s, ps, pc, 2, 403.0));
        OK(coag_sim_advance_to(s, 2.0, NULL));
        OK(coag_sim_particle_count(s, &particles));
        CHECK(particles > 0 && particles < 403, "method %d: refilled, %llu", methods[m],
              (unsigned long long)particles);
        OK(coag_sim_set_counts(s, none, 3, 403.0)); /* drained */
        OK(coag_sim_advance_to(s, 3.0, NULL));
        OK(coag_sim_particle_count(s, &particles));
        CHECK(particles == 0, "method %d: drained", methods[m]);
        coag_sim_free(s);
    }
    coag_kernel_free(k1);
}

#include <time.h>
#define TIMED(call)                                                                \
    do {                                                                           \
        clock_t c0_ = clock();                                                     \
        call;                                                                      \
        printf("  %s: %.1f s\n", #call, (double)(clock() - c0_) / CLOCKS_PER_SEC); \
    } while (0)

int main(void) {
    coag_kernel *k;
    OK(coag_kernel_new_additive(0.0, &k));
    TIMED(corrupted_checkpoints(k));
    quick = getenv("COAG_TEST_QUICK") != NULL;
    TIMED(crafted_checkpoints(k, quick ? 40 : 600));
    TIMED(foreign_checkpoints());
    TIMED(bounded_and_split_calls(k));
    TIMED(reproducers(k));
    TIMED(coupling(k));
    TIMED(sparse_and_empty());
    coag_kernel_free(k);
    return finish("test_hostile");
}
