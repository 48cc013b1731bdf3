/* Tiny test helpers shared by the C tests. */
#ifndef COAG_TEST_CHECK_H
#define COAG_TEST_CHECK_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

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
            char msg_[256];                                                \
            coag_last_error_message(msg_, sizeof msg_, NULL);              \
            fprintf(stderr, "%s:%d: %s returned %s: %s\n", __FILE__, __LINE__, #call, \
                    coag_status_name(st_), msg_);                          \
            exit(1);                                                       \
        }                                                                  \
    } while (0)

/* Expects a specific status. */
#define EXPECT(call, status)                                               \
    do {                                                                   \
        int st_ = (call);                                                  \
        CHECK(st_ == (status), "%s returned %s, expected %s", #call,      \
              coag_status_name(st_), coag_status_name(status));            \
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

static int finish(const char *name) {
    printf("%s: %d passed, %d failed\n", name, checks - failures, failures);
    return failures == 0 ? 0 : 1;
}

#endif
