/* Many simulations in one process, stepped from several threads (a host with one
 * simulation per grid cell): handles share nothing, so cells stepped by two pthreads
 * that take cells in whatever order they come end in exactly the states (checkpoint
 * bytes) of the same cells stepped by one thread; and each thread reads its own last
 * error. */
#define _POSIX_C_SOURCE 200112L /* pthread barriers under -std=c11 */
#include <pthread.h>
#include <stdatomic.h>
#include <string.h>

#include "check.h"

enum { MAX_CELLS = 96, PARTICLES = 1000, STEPS = 8, THREADS = 2 };
/* 96 cells; 16 in the quick mode (COAG_TEST_QUICK, under valgrind) */
static long CELLS = MAX_CELLS;

/* Cell c: the low-rank scheme, Brownian kernel, PARTICLES monomers in volume PARTICLES
 * (M0 = 1), its own stream (seed 11, stream c). */
static coag_sim *make_cell(long c) {
    coag_kernel *k = KERNEL0("brownian");
    coag_options *o = options_seeded(11, (uint64_t)c);
    uint64_t counts[1] = {PARTICLES};
    coag_sim *sim = sim_counts("lowrank", k, o, counts, 1, (double)PARTICLES);
    coag_options_free(o);
    coag_kernel_free(k);
    return sim;
}

typedef struct {
    coag_sim **cells;
    atomic_long next;
    double t;
    atomic_int failed;
} work;

static void *worker(void *arg) {
    work *w = arg;
    long c;
    while ((c = atomic_fetch_add(&w->next, 1)) < CELLS) {
        coag_step_report rep;
        coag_step_report_init(&rep, sizeof rep);
        if (coag_sim_advance_to(w->cells[c], w->t, &rep) != COAG_OK) atomic_store(&w->failed, 1);
    }
    return NULL;
}

/* a bad call on this thread (a sim: a target time in the past; none: a kernel with a
 * parameter out of range), then (both threads having made theirs) its message names
 * its own failure */
static pthread_barrier_t both_failed;

static void *own_error(void *arg) {
    coag_sim *sim = arg;
    int expect_time = sim != NULL;
    coag_kernel *k = NULL;
    int st = expect_time ? coag_sim_advance_to(sim, -1.0, NULL)
                         : coag_kernel_new("product", (const double[]){-2.0}, 1, &k);
    coag_kernel_free(k); /* NULL unless the call wrongly succeeded */
    pthread_barrier_wait(&both_failed);
    char msg[256];
    coag_last_error_message(msg, sizeof msg, NULL);
    int mine = st != COAG_OK && (expect_time ? strstr(msg, "time") != NULL
                                             : strstr(msg, "time") == NULL && msg[0] != 0);
    return mine ? (void *)1 : NULL;
}

static size_t state(coag_sim *sim, unsigned char **out) {
    size_t len, written;
    OK(coag_sim_checkpoint_size(sim, &len));
    *out = malloc(len);
    OK(coag_sim_checkpoint(sim, *out, len, &written));
    return written;
}

int main(void) {
    if (test_quick()) CELLS = 16;
    coag_sim *serial[MAX_CELLS], *threaded[MAX_CELLS];
    for (long c = 0; c < CELLS; c++) {
        serial[c] = make_cell(c);
        threaded[c] = make_cell(c);
    }
    for (int s = 1; s <= STEPS; s++) {
        double t = 0.125 * s;
        for (long c = 0; c < CELLS; c++) OK(coag_sim_advance_to(serial[c], t, NULL));
        work w = {.cells = threaded, .t = t};
        atomic_init(&w.next, 0);
        atomic_init(&w.failed, 0);
        pthread_t th[THREADS];
        for (int i = 0; i < THREADS; i++) CHECK(pthread_create(&th[i], NULL, worker, &w) == 0, "create");
        for (int i = 0; i < THREADS; i++) pthread_join(th[i], NULL);
        CHECK(atomic_load(&w.failed) == 0, "a threaded step failed at t = %g", t);
    }
    int same = 0;
    double m0 = 0.0;
    for (long c = 0; c < CELLS; c++) {
        unsigned char *a, *b;
        size_t la = state(serial[c], &a), lb = state(threaded[c], &b);
        same += la == lb && memcmp(a, b, la) == 0;
        free(a);
        free(b);
        double v;
        OK(coag_sim_moment(threaded[c], 0.0, &v));
        m0 += v / CELLS;
    }
    CHECK(same == CELLS, "%d of %ld cells stepped from %d threads match the serial run", same, CELLS,
          THREADS);
    /* the cells did evolve (M0 = 1 at the start; ~0.33 at t = 1 for this kernel) and
     * not all alike (independent streams) */
    CHECK(m0 > 0.2 && m0 < 0.5, "mean M0 at t = 1: %g", m0);
    double a, b;
    OK(coag_sim_moment(threaded[0], 0.0, &a));
    OK(coag_sim_moment(threaded[1], 0.0, &b));
    CHECK(a != b, "cells 0 and 1 ended alike (M0 %g)", a);

    pthread_t e1, e2;
    void *r1, *r2;
    pthread_barrier_init(&both_failed, NULL, 2);
    CHECK(pthread_create(&e1, NULL, own_error, threaded[0]) == 0, "create");
    CHECK(pthread_create(&e2, NULL, own_error, NULL) == 0, "create");
    pthread_join(e1, &r1);
    pthread_join(e2, &r2);
    CHECK(r1 != NULL && r2 != NULL, "each thread reads its own last error");
    pthread_barrier_destroy(&both_failed);

    for (long c = 0; c < CELLS; c++) {
        coag_sim_free(serial[c]);
        coag_sim_free(threaded[c]);
    }
    printf("(%ld cells x %d particles, %d threads, %d steps) ", CELLS, PARTICLES, THREADS, STEPS);
    return finish("test_cells");
}
