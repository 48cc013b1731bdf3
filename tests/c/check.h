/* Tiny test helpers shared by the C tests. */
#ifndef COAG_TEST_CHECK_H
#define COAG_TEST_CHECK_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "coagula.h"

static int failures = 0;
static int checks = 0;

#define CHECK(cond, ...)                                                   \
    do {                                                                   \
        checks++;                                                          \
        if (!(cond)) {                                                     \
            failures++;                                                    \
            fprintf(stderr, "%s:%d: check failed: %s: ", __FILE__, __LINE__, #cond); \
            fprintf(stderr, __VA_ARGS__);                                  \
            fprintf(stderr, "\n");                                         \
        }                                                                  \
    } while (0)

/* Calls a coag_* function and aborts the test on a non-OK status. */
#define OK(call)                                                           \
    do {                                                                   \
        int st_ = (call);                                                  \
        checks++;                                                          \
        if (st_ != COAG_OK) {                                              \
            char msg_[512];                                                \
            coag_last_error_message(msg_, sizeof msg_, NULL);              \
            fprintf(stderr, "%s:%d: %s returned %s: %s\n", __FILE__, __LINE__, #call, \
                    coag_status_name(st_), msg_);                          \
            exit(1);                                                       \
        }                                                                  \
    } while (0)

/* Expects a specific status (the library's message is printed when it differs). */
#define EXPECT(call, status)                                               \
    do {                                                                   \
        int st_ = (call);                                                  \
        CHECK(st_ == (status), "%s returned %s, expected %s", #call,      \
              coag_status_name(st_), coag_status_name(status));            \
        if (st_ != (status) && st_ != COAG_OK) {                           \
            char msg_[512];                                                \
            coag_last_error_message(msg_, sizeof msg_, NULL);              \
            fprintf(stderr, "    (message: %s)\n", msg_);                  \
        }                                                                  \
    } while (0)

/* COAG_TEST_QUICK set (the valgrind run, 20-50x slower): the statistical checks run
 * on fewer particles. Their tolerances come from the replicas' own standard errors,
 * which cover the noise but not the O(1/N) finite-particle bias: in standard errors
 * that bias grows like sqrt(N_full / N_quick), so the quick sizes are kept where the
 * bias stayed well inside the tolerance over several seeds (see each test). The memory
 * checks see the same code paths. */
static inline int test_quick(void) { return getenv("COAG_TEST_QUICK") != NULL; }

/* Running mean and variance (Welford). */
typedef struct {
    double n, mean, m2;
} stats;

static inline void stats_push(stats *s, double x) {
    s->n += 1.0;
    double d = x - s->mean;
    s->mean += d / s->n;
    s->m2 += d * (x - s->mean);
}

static inline double stats_se(const stats *s) { return sqrt(s->m2 / (s->n - 1.0) / s->n); }

static inline int finish(const char *name) {
    printf("%s: %d passed, %d failed\n", name, checks - failures, failures);
    return failures == 0 ? 0 : 1;
}

/* A built-in kernel of core's table by name, with `n` parameters in the table's order
 * (coag_builtin_param; the rest take their defaults). */
static inline coag_kernel *kernel_new(const char *name, size_t n, const double *params) {
    coag_kernel *k = NULL;
    OK(coag_kernel_new(name, params, n, &k));
    return k;
}
#define KERNEL0(name) kernel_new((name), 0, NULL)
#define KERNEL1(name, a) kernel_new((name), 1, (const double[]){(a)})
#define KERNEL2(name, a, b) kernel_new((name), 2, (const double[]){(a), (b)})
#define KERNEL3(name, a, b, c) kernel_new((name), 3, (const double[]){(a), (b), (c)})

/* New options, every key at its default. */
static inline coag_options *options_new(void) {
    coag_options *o = NULL;
    OK(coag_options_new(&o));
    return o;
}

/* New options with `seed` and `stream` (the sim's own random stream). */
static inline coag_options *options_seeded(uint64_t seed, uint64_t stream) {
    coag_options *o = options_new();
    OK(coag_options_set_count(o, "seed", seed));
    OK(coag_options_set_count(o, "stream", stream));
    return o;
}

/* A sim of `scheme` from counts (`counts[i]` particles of size i + 1) in `volume`. */
static inline coag_sim *sim_counts(const char *scheme, const coag_kernel *k, const coag_options *o,
                                   const uint64_t *counts, size_t len, double volume) {
    coag_sim *s = NULL;
    OK(coag_sim_new_counts(scheme, k, NULL, o, counts, len, volume, &s));
    return s;
}

/* The total of counts[0 .. len) as a double (the old default volume: the particle number). */
static inline double count_total(const uint64_t *counts, size_t len) {
    double n = 0.0;
    for (size_t i = 0; i < len; i++) n += (double)counts[i];
    return n;
}

/* A checkpoint of `s` (malloc'ed; length in *n). */
static inline uint8_t *snapshot(const coag_sim *s, size_t *n) {
    OK(coag_sim_checkpoint_size(s, n));
    uint8_t *b = malloc(*n ? *n : 1);
    size_t written = 0;
    OK(coag_sim_checkpoint(s, b, *n, &written));
    *n = written;
    return b;
}

/* Whether two sims hold the same checkpoint (state, stream, settings). */
static inline int same_sim(const coag_sim *a, const coag_sim *b) {
    size_t na, nb;
    uint8_t *x = snapshot(a, &na), *y = snapshot(b, &nb);
    int eq = na == nb && memcmp(x, y, na) == 0;
    free(x);
    free(y);
    return eq;
}

/* Whether a sim's checkpoint equals the bytes `b` (length n). */
static inline int sim_is(const coag_sim *s, const uint8_t *b, size_t n) {
    size_t m;
    uint8_t *x = snapshot(s, &m);
    int eq = m == n && memcmp(x, b, n) == 0;
    free(x);
    return eq;
}

#endif
