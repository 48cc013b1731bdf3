/* A worked host: a plug-flow aerosol reactor as a row of well-mixed cells along a pipe.
 *
 * The gas carries particles from cell to cell (residence time TAU per cell); monomers
 * nucleate in the first cells (a source), grow by condensation there (monomer
 * attachment at G(x) = g x^(2/3), free-molecular vapour uptake), and coagulate
 * everywhere (the constant kernel). Each cell is one coag_sim with its own processes;
 * the host moves particles: every host step DT, each particle of a cell leaves for the
 * next cell with probability 1 - exp(-DT/TAU) (the last cell's leave the pipe), read
 * with coag_sim_get_pairs and written back with coag_sim_set_pairs.
 *
 * Checked two ways:
 *  - the books balance exactly: particles and mass in the cells = injected - merged
 *    (number) / + grown (mass) - what left the pipe, the injected and grown from the
 *    cells' books (coag_sim_books, read before each coag_sim_set_pairs restarts them),
 *    the merges from the sims' totals (coag_sim_totals: every call);
 *  - against core's sectional reference (coag_sectional_*) of the same cells with the
 *    same operator splitting (the sectional solution advanced over DT, then the
 *    fraction 1 - exp(-DT/TAU) of every pivot moved on): M0 and M1 of every cell at
 *    the end, the particle side averaged over REPLICAS independent reactors, within
 *    T_THRESHOLD standard errors plus the sectional grid's error, bounded by the
 *    difference between its solutions at pivot ratios 1.05 and 1.10 (second order in
 *    the ratio - 1: about three times the fine grid's error).
 *
 *   cc -O2 -Iinclude examples/c/plug_flow.c target/release/libcoagula.a -lpthread -ldl -lm
 *   ./a.out [particles per unit concentration = 2000]
 * Exit status 0 when both checks pass.
 */
#include <coagula.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CELLS 6
#define REPLICAS 16
/* Student t, 15 degrees of freedom, two-sided 1e-6 per check: 12 checks keep the
 * family-wise false alarm near 1e-5 (docs/design/statistical-tests.md) */
#define T_THRESHOLD 7.90
#define TAU 1.0       /* residence time per cell */
#define DT 0.05       /* host step */
#define T_END 8.0     /* past the pipe's residence time CELLS * TAU: near steady state */
#define SOURCE 2.0    /* monomers per unit volume and time, cells 0 and 1 */
#define GROWTH 0.3    /* g in G(x) = g x^(2/3), cells 0 to 2 */
#define MAXPAIRS 100000

static void die(int status, const char *what) {
    char msg[256];
    coag_last_error_message(msg, sizeof msg, NULL);
    fprintf(stderr, "%s: %s: %s\n", what, coag_status_name(status), msg);
    exit(2);
}
#define OK(call)                          \
    do {                                  \
        int32_t st_ = (call);             \
        if (st_ != COAG_OK) die(st_, #call); \
    } while (0)

/* the host's own random numbers (for the transfer): splitmix64 */
static uint64_t host_state = 0x9e3779b97f4a7c15u;
static double uniform(void) {
    uint64_t z = (host_state += 0x9e3779b97f4a7c15u);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

/* binomial(n, p) by n Bernoulli trials (n is a cell's count at one size) */
static uint64_t binomial(uint64_t n, double p) {
    uint64_t k = 0;
    for (uint64_t i = 0; i < n; i++) k += uniform() < p;
    return k;
}

typedef struct {
    double injected_n, injected_m, grown_m;
} tally;

/* what a cell's processes did since they were set (cells without: nothing) */
static void read_books(coag_sim *s, int k, tally *t) {
    if (k >= 3) return;
    coag_books b;
    memset(&b, 0, sizeof b);
    b.struct_size = sizeof b;
    OK(coag_sim_books(s, &b));
    t->injected_n += (double)b.injected_number;
    t->injected_m += b.injected_mass;
    t->grown_m += b.grown_mass;
}

/* a cell's processes (a fresh set after every set_pairs: the books restart) */
static void cell_processes(coag_sim *s, int k) {
    if (k < 2) OK(coag_sim_set_source(s, SOURCE, COAG_SOURCE_MONODISPERSE, 1.0, 0.0));
    if (k < 3) OK(coag_sim_set_growth(s, GROWTH, 2.0 / 3.0));
}

/* pairs of one cell */
typedef struct {
    uint64_t size[MAXPAIRS], count[MAXPAIRS];
    size_t len;
} pairs;

/* one reactor of particles to T_END; moments of every cell at the end; 0 when the
 * books balance */
static int run_particles(const coag_kernel *k, double volume, uint64_t seed, double m0[CELLS],
                         double m1[CELLS]) {
    static pairs cell[CELLS], leave[CELLS];
    coag_sim *sims[CELLS];
    tally books = {0, 0, 0};
    double out_n = 0.0, out_m = 0.0;
    for (int c = 0; c < CELLS; c++) {
        coag_options *o;
        OK(coag_options_new(&o));
        OK(coag_options_set_count(o, "seed", seed));
        OK(coag_options_set_count(o, "stream", (uint64_t)c));
        OK(coag_sim_new_counts("lowrank", k, NULL, o, NULL, 0, volume, &sims[c]));
        coag_options_free(o);
        cell_processes(sims[c], c);
    }
    host_state = seed * 0x2545f4914f6cdd1du + 1;
    double f = 1.0 - exp(-DT / TAU);
    int steps = (int)lround(T_END / DT);
    for (int step = 1; step <= steps; step++) {
        double t = step * DT;
        for (int c = 0; c < CELLS; c++) OK(coag_sim_advance_to(sims[c], t, NULL));
        /* who leaves, from the states before any transfer */
        for (int c = 0; c < CELLS; c++) {
            OK(coag_sim_get_pairs(sims[c], cell[c].size, cell[c].count, MAXPAIRS, NULL, &cell[c].len));
            leave[c].len = cell[c].len;
            for (size_t i = 0; i < cell[c].len; i++) {
                leave[c].size[i] = cell[c].size[i];
                leave[c].count[i] = binomial(cell[c].count[i], f);
                cell[c].count[i] -= leave[c].count[i];
            }
        }
        for (size_t i = 0; i < leave[CELLS - 1].len; i++) {
            out_n += (double)leave[CELLS - 1].count[i];
            out_m += (double)leave[CELLS - 1].count[i] * (double)leave[CELLS - 1].size[i];
        }
        /* cell c gets what cell c - 1 lost: merge the two ascending lists */
        for (int c = CELLS - 1; c >= 0; c--) {
            static pairs merged;
            size_t a = 0, b = 0;
            merged.len = 0;
            const pairs *in = c > 0 ? &leave[c - 1] : NULL;
            size_t nb = in ? in->len : 0;
            while (a < cell[c].len || b < nb) {
                uint64_t sa = a < cell[c].len ? cell[c].size[a] : UINT64_MAX;
                uint64_t sb = b < nb ? in->size[b] : UINT64_MAX;
                uint64_t s = sa < sb ? sa : sb, n = 0;
                if (sa == s) n += cell[c].count[a++];
                if (sb == s) n += in->count[b++];
                if (n > 0) {
                    if (merged.len == MAXPAIRS) die(COAG_CAPACITY, "pairs");
                    merged.size[merged.len] = s;
                    merged.count[merged.len++] = n;
                }
            }
            read_books(sims[c], c, &books);
            OK(coag_sim_set_pairs(sims[c], merged.size, merged.count, merged.len, volume));
            cell_processes(sims[c], c);
        }
    }
    /* the balance, exactly: sizes and counts are integers below 2^53 */
    double n_in = 0.0, m_in = 0.0, merged = 0.0;
    for (int c = 0; c < CELLS; c++) {
        read_books(sims[c], c, &books);
        /* coagulations: the sim's totals over every call (set_pairs keeps them) */
        coag_step_report tot;
        memset(&tot, 0, sizeof tot);
        tot.struct_size = sizeof tot;
        OK(coag_sim_totals(sims[c], &tot));
        merged += (double)tot.events;
        uint64_t n;
        OK(coag_sim_particle_count(sims[c], &n));
        OK(coag_sim_get_pairs(sims[c], cell[c].size, cell[c].count, MAXPAIRS, NULL, &cell[c].len));
        double mass = 0.0;
        for (size_t i = 0; i < cell[c].len; i++) mass += (double)cell[c].size[i] * (double)cell[c].count[i];
        n_in += (double)n;
        m_in += mass;
        OK(coag_sim_moment(sims[c], 0.0, &m0[c]));
        OK(coag_sim_moment(sims[c], 1.0, &m1[c]));
        coag_sim_free(sims[c]);
    }
    int ok = n_in == books.injected_n - merged - out_n && m_in == books.injected_m + books.grown_m - out_m;
    printf("seed %llu: in the cells %.0f particles of mass %.0f; injected %.0f (mass %.0f), merged %.0f, grown %.0f, "
           "left the pipe %.0f (mass %.0f): %s\n",
           (unsigned long long)seed, n_in, m_in, books.injected_n, books.injected_m, merged, books.grown_m,
           out_n, out_m, ok ? "balanced exactly" : "NOT BALANCED");
    return ok ? 0 : 1;
}

/* the same reactor, deterministic: the sectional reference per cell */
static void run_sectional(const coag_kernel *k, double ratio, double m0[CELLS], double m1[CELLS]) {
    /* integer pivots to 64 (where growth by attachment is the chain's mean exactly),
     * then the ratio to past 8192 */
    double x[256];
    size_t len = 0;
    for (int i = 1; i <= 64; i++) x[len++] = i;
    while (x[len - 1] < 8192.0 && len < 256) {
        x[len] = floor(x[len - 1] * ratio);
        if (x[len] <= x[len - 1]) x[len] = x[len - 1] + 1.0;
        len++;
    }
    coag_sectional *s[CELLS];
    double n[CELLS][256], moved[CELLS][256];
    for (int c = 0; c < CELLS; c++) {
        OK(coag_sectional_new(k, x, len, &s[c]));
        OK(coag_sectional_set_processes(s[c], c < 2 ? SOURCE : 0.0, 1.0, 0.0, 0.0, c < 3 ? GROWTH : 0.0,
                                        2.0 / 3.0));
    }
    double f = 1.0 - exp(-DT / TAU);
    int steps = (int)lround(T_END / DT);
    for (int step = 1; step <= steps; step++) {
        for (int c = 0; c < CELLS; c++) {
            OK(coag_sectional_advance_to(s[c], step * DT, 1e-2));
            OK(coag_sectional_numbers(s[c], n[c], len));
            for (size_t i = 0; i < len; i++) moved[c][i] = f * n[c][i];
        }
        for (int c = 0; c < CELLS; c++) {
            for (size_t i = 0; i < len; i++) n[c][i] += (c > 0 ? moved[c - 1][i] : 0.0) - moved[c][i];
            OK(coag_sectional_set_numbers(s[c], n[c], len));
        }
    }
    for (int c = 0; c < CELLS; c++) {
        OK(coag_sectional_moment(s[c], 0.0, &m0[c], NULL));
        OK(coag_sectional_moment(s[c], 1.0, &m1[c], NULL));
        coag_sectional_free(s[c]);
    }
}

int main(int argc, char **argv) {
    double volume = argc > 1 ? atof(argv[1]) : 2000.0;
    if (!(volume >= 10.0)) {
        fprintf(stderr, "particles per unit concentration: at least 10\n");
        return 2;
    }
    coag_kernel *k;
    OK(coag_kernel_new("constant", (const double[]){1.0}, 1, &k));
    double p0[REPLICAS][CELLS], p1[REPLICAS][CELLS], s0[CELLS], s1[CELLS], c0[CELLS], c1[CELLS];
    int failed = 0;
    for (int r = 0; r < REPLICAS; r++) failed |= run_particles(k, volume, 11 + (uint64_t)r, p0[r], p1[r]);
    run_sectional(k, 1.05, s0, s1);
    run_sectional(k, 1.10, c0, c1);
    printf("cell   M0 particles (±SE)    M0 sectional (grid)      M1 particles (±SE)    M1 sectional (grid)\n");
    for (int c = 0; c < CELLS; c++) {
        double mean[2] = {0, 0}, var[2] = {0, 0}, ref[2] = {s0[c], s1[c]};
        double grid[2] = {fabs(s0[c] - c0[c]), fabs(s1[c] - c1[c])};
        for (int r = 0; r < REPLICAS; r++) {
            mean[0] += p0[r][c] / REPLICAS;
            mean[1] += p1[r][c] / REPLICAS;
        }
        for (int r = 0; r < REPLICAS; r++) {
            var[0] += (p0[r][c] - mean[0]) * (p0[r][c] - mean[0]) / (REPLICAS - 1);
            var[1] += (p1[r][c] - mean[1]) * (p1[r][c] - mean[1]) / (REPLICAS - 1);
        }
        int ok = 1;
        for (int j = 0; j < 2; j++) {
            double se = sqrt(var[j] / REPLICAS);
            ok &= fabs(mean[j] - ref[j]) <= T_THRESHOLD * se + grid[j];
        }
        printf("%4d   %.5f (±%.5f)   %.5f (%.1e)   %.4f (±%.4f)    %.4f (%.1e)   %s\n", c, mean[0],
               sqrt(var[0] / REPLICAS), s0[c], grid[0], mean[1], sqrt(var[1] / REPLICAS), s1[c], grid[1],
               ok ? "ok" : "OFF");
        failed |= !ok;
    }
    coag_kernel_free(k);
    printf("plug flow: %s\n", failed ? "FAILED" : "balanced and within the sectional reference");
    return failed;
}
