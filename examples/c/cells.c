/* One coagulation simulation per grid cell, as a CFD or process code embeds them:
 * NCELLS independent low-rank sims (Brownian kernel, PARTICLES monomers each) owned by
 * one process and advanced by an OpenMP loop over the cells, one host time step at a
 * time. Handles share nothing, so any thread may step any cell (one thread per handle
 * at a time).
 *
 * Prints the memory per cell (resident set growth over the creation of the cells),
 * the cost of stepping an idle cell on one core (a host step too short for any event,
 * and a step to the time the cell already has), and the throughput of real steps on
 * the OpenMP threads.
 *
 *   cc -O2 -fopenmp -Iinclude examples/c/cells.c target/release/libcoagula.a \
 *      -lpthread -ldl -lm -o cells
 *   ./cells [cells=10000] [particles=1000] [threads=all]
 */
#include <coagula.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void die(int status, const char *what) {
    char msg[256];
    coag_last_error_message(msg, sizeof msg, NULL);
    fprintf(stderr, "%s: %s: %s\n", what, coag_status_name(status), msg);
    exit(1);
}

/* resident set size in bytes (Linux) */
static double rss_bytes(void) {
    long pages = 0, resident = 0;
    FILE *f = fopen("/proc/self/statm", "r");
    if (!f || fscanf(f, "%ld %ld", &pages, &resident) != 2) {
        if (f) fclose(f);
        return 0.0;
    }
    fclose(f);
    return (double)resident * 4096.0;
}

/* advances every cell to t; returns the events of the loop (errors are fatal) */
static unsigned long long step_all(coag_sim **cells, long n, double t) {
    unsigned long long events = 0;
    int failed = COAG_OK;
    char why[256] = "";
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : events)
    for (long c = 0; c < n; c++) {
        coag_step_report rep;
        coag_step_report_init(&rep, sizeof rep);
        int s = coag_sim_advance_to(cells[c], t, &rep);
        if (s != COAG_OK) {
            /* the message is this thread's: copy it here */
#pragma omp critical
            {
                failed = s;
                coag_last_error_message(why, sizeof why, NULL);
            }
        }
        events += rep.events;
    }
    if (failed != COAG_OK) {
        fprintf(stderr, "coag_sim_advance_to: %s: %s\n", coag_status_name(failed), why);
        exit(1);
    }
    return events;
}

/* advances every cell to t on this thread alone; returns the events */
static unsigned long long serial_steps(coag_sim **cells, long n, double t) {
    unsigned long long events = 0;
    for (long c = 0; c < n; c++) {
        coag_step_report rep;
        coag_step_report_init(&rep, sizeof rep);
        int s = coag_sim_advance_to(cells[c], t, &rep);
        if (s != COAG_OK) die(s, "coag_sim_advance_to");
        events += rep.events;
    }
    return events;
}

int main(int argc, char **argv) {
    long ncells = argc > 1 ? atol(argv[1]) : 10000;
    long particles = argc > 2 ? atol(argv[2]) : 1000;
    int nthreads = argc > 3 ? atoi(argv[3]) : omp_get_max_threads();
    if (ncells < 1 || particles < 2 || nthreads < 1) {
        fprintf(stderr, "usage: %s [cells >= 1] [particles >= 2] [threads >= 1]\n", argv[0]);
        return 2;
    }
    omp_set_num_threads(nthreads);
    coag_kernel *k;
    int s = coag_kernel_new("brownian", NULL, 0, &k); /* K = (x^1/3 + y^1/3)(x^-1/3 + y^-1/3) */
    if (s != COAG_OK) die(s, "coag_kernel_new");
    coag_options *opts;
    s = coag_options_new(&opts);
    if (s != COAG_OK) die(s, "coag_options_new");
    s = coag_options_set_count(opts, "seed", 2026);
    if (s != COAG_OK) die(s, "coag_options_set_count");
    uint64_t counts[1] = {(uint64_t)particles}; /* all monomers */

    coag_sim **cells = malloc((size_t)ncells * sizeof *cells);
    if (!cells) return 1;
    double rss0 = rss_bytes();
    for (long c = 0; c < ncells; c++) {
        s = coag_options_set_count(opts, "stream", (uint64_t)c); /* an independent stream per cell */
        if (s != COAG_OK) die(s, "coag_options_set_count");
        /* the low-rank scheme (bucketed layout); volume = particles, so M0 = 1 */
        s = coag_sim_new_counts("lowrank", k, NULL, opts, counts, 1, (double)particles, &cells[c]);
        if (s != COAG_OK) die(s, "coag_sim_new_counts");
    }
    double per_cell = (rss_bytes() - rss0) / (double)ncells;
    coag_options_free(opts); /* the sims copied what they need */
    coag_kernel_free(k);

    int threads = omp_get_max_threads();
    printf("%ld cells x %ld particles (Brownian kernel, low-rank bucketed), %d threads\n", ncells,
           particles, threads);
    printf("memory per cell at the start: %.1f KiB\n", per_cell / 1024.0);

    /* a first call builds each cell's proposal tables: not an idle step */
    double t = 0.0;
    step_all(cells, ncells, t);
    /* the cost of one call on one core, the fastest of 5 passes over every cell: a
     * step to the time the cell already has, and an idle step (1e-7 of a time unit,
     * where a cell of 1e3 particles expects ~2e-4 events) */
    double same = 1e30, idle = 1e30;
    unsigned long long idle_events = 0;
    for (int pass = 0; pass < 5; pass++) {
        double w = omp_get_wtime();
        serial_steps(cells, ncells, t);
        double d = (omp_get_wtime() - w) / (double)ncells;
        if (d < same) same = d;
        t += 1e-7;
        w = omp_get_wtime();
        idle_events += serial_steps(cells, ncells, t);
        d = (omp_get_wtime() - w) / (double)ncells;
        if (d < idle) idle = d;
    }
    /* an observable read: M0 of every cell, fastest of 5 passes */
    double read = 1e30, sink = 0.0;
    for (int pass = 0; pass < 5; pass++) {
        double w = omp_get_wtime();
        for (long c = 0; c < ncells; c++) {
            double v;
            s = coag_sim_moment(cells[c], 0.0, &v);
            if (s != COAG_OK) die(s, "coag_sim_moment");
            sink += v;
        }
        double d = (omp_get_wtime() - w) / (double)ncells;
        if (d < read) read = d;
    }
    printf("one call on one core (fastest of 5 passes): step to the current time %.1f ns, "
           "idle step %.1f ns (%llu events in %ld idle cell steps), moment(0) %.1f ns "
           "(sum %.0f)\n",
           same * 1e9, idle * 1e9, idle_events, 5 * ncells, read * 1e9, sink);

    /* real steps: 10 host steps to t = 1 */
    unsigned long long events = 0;
    double w = omp_get_wtime();
    for (int step = 1; step <= 10; step++) events += step_all(cells, ncells, t + 0.1 * step);
    double busy = omp_get_wtime() - w;
    double m0 = 0.0;
    for (long c = 0; c < ncells; c++) {
        double v;
        s = coag_sim_moment(cells[c], 0.0, &v);
        if (s != COAG_OK) die(s, "coag_sim_moment");
        m0 += v / (double)ncells;
    }
    printf("10 steps to t = 1: %.3f s, %llu events, %.2f M events/s, %.0f cell steps/s; mean "
           "M0 %.4f\n",
           busy, events, (double)events / busy / 1e6, 10.0 * (double)ncells / busy, m0);
    printf("memory per cell at t = 1: %.1f KiB (peak RSS %.1f MiB)\n",
           (rss_bytes() - rss0) / (double)ncells / 1024.0, rss_bytes() / 1048576.0);
    for (long c = 0; c < ncells; c++) coag_sim_free(cells[c]);
    free(cells);
    return 0;
}
