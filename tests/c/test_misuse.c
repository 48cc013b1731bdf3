/* Misuse of the C ABI: NULL handles and outputs, zero lengths, too-small buffers, NaN
 * parameters, unknown names, wrong scheme, bad checkpoints, and use after a failed
 * call. Every call must return an error code (never crash), leave outputs untouched and
 * the handle usable. Built with -fsanitize=address,undefined. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "check.h"

static double nan_kernel(double x, double y, void *ud) {
    (void)ud;
    return (x + y > 4.0) ? NAN : 1.0;
}

static double unit_rate(double x, void *ud) {
    (void)x;
    (void)ud;
    return 1.0;
}

static double half_piece(double x, double u, void *ud) {
    (void)u;
    (void)ud;
    return 0.5 * x;
}

/* The registry's tables and the options handle: NULL outputs, indices past the end,
 * structs below their first version, unknown keys and names, values of the wrong kind.
 * (The successors of the old per-family config structs and their default_config.) */
static void tables_and_options(void) {
    size_t n = 77, idx = 77;
    OK(coag_scheme_count(&n));
    CHECK(n > 0, "an empty registry");
    EXPECT(coag_scheme_count(NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_scheme_find(NULL, &idx), COAG_NULL_PARAMETER);
    EXPECT(coag_scheme_find("massflow", NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_scheme_find("no-such-scheme", &idx), COAG_INVALID_ARGUMENT);
    CHECK(idx == 77, "index written on error");
    OK(coag_scheme_find("mfa", &idx));
    coag_scheme_info info;
    EXPECT(coag_scheme_info_get(idx, NULL, sizeof info), COAG_NULL_PARAMETER);
    EXPECT(coag_scheme_info_get(idx, &info, 8), COAG_INVALID_ARGUMENT); /* below the first version */
    EXPECT(coag_scheme_info_get(n, &info, sizeof info), COAG_INVALID_ARGUMENT);
    {
        /* a caller with a larger (newer) struct: the known fields are written, nothing past */
        struct {
            coag_scheme_info i;
            uint64_t extra;
        } big;
        memset(&big, 0xab, sizeof big);
        OK(coag_scheme_info_get(idx, &big.i, sizeof big));
        CHECK(big.i.struct_size == sizeof info && big.extra == 0xababababababababull &&
                  strcmp(big.i.name, "mfa") == 0,
              "newer scheme info: known fields only (struct_size %zu)", big.i.struct_size);
    }
    const char *name = "untouched";
    EXPECT(coag_scheme_option(idx, 1000, &name), COAG_INVALID_ARGUMENT);
    EXPECT(coag_scheme_option(n, 0, &name), COAG_INVALID_ARGUMENT);
    EXPECT(coag_scheme_option(idx, 0, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_scheme_observable(idx, 0, &name), COAG_INVALID_ARGUMENT); /* mfa has none */
    CHECK(strcmp(name, "untouched") == 0, "output written on error");
    coag_option_info oi;
    EXPECT(coag_option_count(NULL), COAG_NULL_PARAMETER);
    OK(coag_option_count(&n));
    EXPECT(coag_option_info_get(n, &oi, sizeof oi), COAG_INVALID_ARGUMENT);
    EXPECT(coag_option_info_get(0, &oi, 8), COAG_INVALID_ARGUMENT);
    EXPECT(coag_option_info_get(0, NULL, sizeof oi), COAG_NULL_PARAMETER);
    coag_builtin_info bi;
    coag_param_info pi;
    EXPECT(coag_builtin_count(NULL), COAG_NULL_PARAMETER);
    OK(coag_builtin_count(&n));
    EXPECT(coag_builtin_info_get(n, &bi, sizeof bi), COAG_INVALID_ARGUMENT);
    EXPECT(coag_builtin_info_get(0, &bi, 8), COAG_INVALID_ARGUMENT);
    OK(coag_builtin_info_get(0, &bi, sizeof bi));
    EXPECT(coag_builtin_param(0, bi.param_count, &pi, sizeof pi), COAG_INVALID_ARGUMENT);
    EXPECT(coag_builtin_param(n, 0, &pi, sizeof pi), COAG_INVALID_ARGUMENT);
    EXPECT(coag_builtin_param(0, 0, NULL, sizeof pi), COAG_NULL_PARAMETER);

    coag_options *o = NULL;
    EXPECT(coag_options_new(NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_options_clone(NULL, &o), COAG_NULL_PARAMETER);
    CHECK(o == NULL, "no options written on error");
    o = options_new();
    EXPECT(coag_options_clone(o, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_options_set_real(NULL, "dt", 0.1), COAG_NULL_PARAMETER);
    EXPECT(coag_options_set_real(o, NULL, 0.1), COAG_NULL_PARAMETER);
    EXPECT(coag_options_set_name(o, "points", NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_options_set_real(o, "no-such-key", 0.1), COAG_INVALID_ARGUMENT);
    EXPECT(coag_options_set_real(o, "dt", NAN), COAG_INVALID_ARGUMENT);
    EXPECT(coag_options_set_real(o, "dt", -1.0), COAG_INVALID_ARGUMENT);
    EXPECT(coag_options_set_count(o, "points", 17), COAG_INVALID_ARGUMENT); /* a name, not a count */
    EXPECT(coag_options_set_name(o, "points", "bogus"), COAG_INVALID_ARGUMENT);
    EXPECT(coag_options_set_name(o, "dt", "fast"), COAG_INVALID_ARGUMENT);
    EXPECT(coag_options_set_real(o, "size-limit", 2.5), COAG_INVALID_ARGUMENT); /* a fraction */
    EXPECT(coag_options_set_real(o, "size-limit", 1.0), COAG_INVALID_ARGUMENT); /* >= 2 */
    EXPECT(coag_options_set_flag(o, "seed", 1), COAG_INVALID_ARGUMENT);
    /* the refused values changed nothing: a sim built with them equals one built with
     * every default (settings and stream are in the checkpoint) */
    {
        coag_kernel *k = KERNEL1("constant", 1.0);
        double x[4] = {1, 1, 1, 1};
        coag_sim *a = NULL, *b = NULL;
        OK(coag_sim_new_sizes("massflow", k, NULL, o, x, 4, 1.0, &a));
        OK(coag_sim_new_sizes("massflow", k, NULL, NULL, x, 4, 1.0, &b));
        CHECK(same_sim(a, b), "refused option values changed the options");
        coag_sim_free(a);
        coag_sim_free(b);
        coag_kernel_free(k);
    }
    coag_options_free(o);
    coag_options_free(NULL);
}

int main(void) {
    coag_kernel *k = NULL;
    coag_fragmentation *f = NULL;
    coag_sim *s = NULL;
    double d = -7.0;
    uint64_t u = 77;
    size_t z = 77;

    /* constructors: NULL outs, NaN and out-of-range parameters, unknown names */
    EXPECT(coag_kernel_new("constant", (const double[]){1.0}, 1, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_kernel_new(NULL, NULL, 0, &k), COAG_NULL_PARAMETER);
    EXPECT(coag_kernel_new("constant", NULL, 1, &k), COAG_NULL_PARAMETER); /* n params from NULL */
    EXPECT(coag_kernel_new("constant", (const double[]){NAN}, 1, &k), COAG_INVALID_ARGUMENT);
    EXPECT(coag_kernel_new("constant", (const double[]){-1.0}, 1, &k), COAG_INVALID_ARGUMENT);
    EXPECT(coag_kernel_new("product", (const double[]){1.5}, 1, &k), COAG_INVALID_ARGUMENT);
    EXPECT(coag_kernel_new("product", NULL, 0, &k), COAG_INVALID_ARGUMENT); /* a is required */
    EXPECT(coag_kernel_new("homogeneous", (const double[]){0.5}, 1, &k), COAG_INVALID_ARGUMENT);
    EXPECT(coag_kernel_new("additive", (const double[]){1.0, -1.0}, 2, &k), COAG_INVALID_ARGUMENT); /* min-size */
    /* more parameters than the kernel has: a buffer of the wrong length */
    EXPECT(coag_kernel_new("constant", (const double[]){1.0, 2.0}, 2, &k), COAG_BUFFER_TOO_SMALL);
    EXPECT(coag_kernel_new("no-such-kernel", NULL, 0, &k), COAG_INVALID_ARGUMENT);
    CHECK(k == NULL, "no handle written on error");
    EXPECT(coag_fragmentation_new_binary_uniform(0.0, &f), COAG_INVALID_ARGUMENT);
    EXPECT(coag_fragmentation_new_binary_uniform(1.0, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_kernel_new_user(NULL, &k), COAG_NULL_PARAMETER);
    coag_user_kernel bad = {NULL, NULL, 0, NULL, 0, NULL, NULL};
    EXPECT(coag_kernel_new_user(&bad, &k), COAG_INVALID_ARGUMENT);
    bad.rate = nan_kernel;
    bad.rank = 9;
    EXPECT(coag_kernel_new_user(&bad, &k), COAG_INVALID_ARGUMENT);
    bad.rank = 1; /* rank without factors */
    EXPECT(coag_kernel_new_user(&bad, &k), COAG_INVALID_ARGUMENT);
    coag_user_fragmentation badf = {NULL, NULL, -1.0, NULL};
    EXPECT(coag_fragmentation_new_user(&badf, &f), COAG_INVALID_ARGUMENT);
    badf.rate = unit_rate;
    badf.inverse_piece = half_piece;
    badf.sup_rate = NAN;
    EXPECT(coag_fragmentation_new_user(&badf, &f), COAG_INVALID_ARGUMENT);
    CHECK(f == NULL, "no handle written on error");

    /* the last error message, with a too-small buffer and a length query */
    char small[4];
    size_t len = 0;
    EXPECT(coag_last_error_message(small, sizeof small, &len), COAG_BUFFER_TOO_SMALL);
    CHECK(len > 4 && small[3] == '\0', "truncated and terminated");
    EXPECT(coag_last_error_message(NULL, 0, &len), COAG_OK);
    EXPECT(coag_last_error_message(NULL, 5, &len), COAG_NULL_PARAMETER);
    EXPECT(coag_last_error_message(small, 0, &len), COAG_BUFFER_TOO_SMALL);
    CHECK(strcmp(coag_status_name(12345), "COAG_UNKNOWN") == 0, "unknown status name");

    tables_and_options();

    k = KERNEL1("constant", 1.0);
    EXPECT(coag_kernel_rate(k, 1.0, 2.0, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_kernel_rate(NULL, 1.0, 2.0, &d), COAG_NULL_PARAMETER);
    {
        /* a temperature model has no K(x, y) */
        coag_kernel *tk = KERNEL0("temperature-ballistic");
        EXPECT(coag_kernel_rate(tk, 1.0, 2.0, &d), COAG_UNSUPPORTED);
        CHECK(d == -7.0, "output untouched on error");
        coag_kernel_free(tk);
    }

    /* sim constructors: the time-driven mass flow */
    double sizes[6] = {1, 1, 1, 1, 1, 1};
    coag_options *mo = options_new();
    EXPECT(coag_sim_new_sizes(NULL, k, NULL, NULL, sizes, 4, 1.0, &s), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_new_sizes("massflow", NULL, NULL, NULL, sizes, 4, 1.0, &s), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_new_sizes("massflow", k, NULL, NULL, NULL, 4, 1.0, &s), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_new_sizes("massflow", k, NULL, NULL, sizes, 4, 1.0, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_new_sizes("massflow", k, NULL, NULL, sizes, 0, 1.0, &s), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_new_sizes("massflow", k, NULL, NULL, sizes, 6, 1.0, &s), COAG_INVALID_ARGUMENT); /* not 2^m */
    EXPECT(coag_sim_new_sizes("massflow", k, NULL, NULL, sizes, 4, NAN, &s), COAG_INVALID_ARGUMENT); /* mass */
    EXPECT(coag_sim_new_sizes("no-such-scheme", k, NULL, NULL, sizes, 4, 1.0, &s), COAG_INVALID_ARGUMENT);
    /* (old: config.points = 17, dt = NaN — now refused when set, see tables_and_options) */
    OK(coag_options_set_name(mo, "points", "mc"));
    OK(coag_options_set_name(mo, "randomization", "owen"));
    /* MC points cannot be randomised: each value is valid, the pair does not apply (the
     * old config's INVALID_ARGUMENT is now the more precise UNSUPPORTED) */
    EXPECT(coag_sim_new_sizes("massflow", k, NULL, mo, sizes, 4, 1.0, &s), COAG_UNSUPPORTED);
    coag_options_free(mo);
    mo = options_new();
    OK(coag_options_set_count(mo, "size-limit", 64)); /* an option massflow does not take */
    EXPECT(coag_sim_new_sizes("massflow", k, NULL, mo, sizes, 4, 1.0, &s), COAG_UNSUPPORTED);
    coag_options_free(mo);
    uint64_t four[1] = {4};
    EXPECT(coag_sim_new_counts("massflow", k, NULL, NULL, four, 1, 4.0, &s), COAG_UNSUPPORTED); /* no counts */
    sizes[2] = -1.0;
    EXPECT(coag_sim_new_sizes("massflow", k, NULL, NULL, sizes, 4, 1.0, &s), COAG_INVALID_ARGUMENT);
    CHECK(s == NULL, "no sim written on error");

    /* the event-driven mass flow algorithm */
    sizes[2] = 1.0;
    EXPECT(coag_sim_new_sizes(NULL, k, NULL, NULL, sizes, 4, 1.0, &s), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_new_sizes("mfa", NULL, NULL, NULL, sizes, 4, 1.0, &s), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_new_sizes("mfa", k, NULL, NULL, NULL, 4, 1.0, &s), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_new_sizes("mfa", k, NULL, NULL, sizes, 4, 1.0, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_new_sizes("mfa", k, NULL, NULL, sizes, 0, 1.0, &s), COAG_INVALID_ARGUMENT);
    {
        /* a temperature model is not a coagulation kernel */
        coag_kernel *tk = KERNEL0("temperature-ballistic");
        EXPECT(coag_sim_new_sizes("mfa", tk, NULL, NULL, sizes, 4, 1.0, &s), COAG_UNSUPPORTED);
        coag_kernel_free(tk);
    }
    CHECK(s == NULL, "no sim written on error");
    OK(coag_sim_new_sizes("mfa", k, NULL, NULL, sizes, 4, 1.0, &s));
    const char *name = "untouched";
    EXPECT(coag_sim_scheme(s, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_scheme(NULL, &name), COAG_NULL_PARAMETER);
    OK(coag_sim_scheme(s, &name));
    CHECK(strcmp(name, "mfa") == 0, "scheme %s", name);
    EXPECT(coag_sim_set_dt(s, 0.1), COAG_UNSUPPORTED);
    size_t ewb;
    EXPECT(coag_sim_workspace_size(NULL, NULL, NULL, 4, &ewb), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_workspace_size("mfa", NULL, NULL, 4, NULL), COAG_NULL_PARAMETER);
    /* a workspace whose size overflows: COAG_CAPACITY, as the old query said and as
     * coag_sim_new_sizes says of the same overflow ("integer overflow in workspace size") */
    EXPECT(coag_sim_workspace_size("mfa", NULL, NULL, SIZE_MAX, &ewb), COAG_CAPACITY);
    OK(coag_sim_workspace_size("mfa", NULL, NULL, 4, &ewb));
    coag_sim *es = NULL;
    EXPECT(coag_sim_new_sizes_in("mfa", k, NULL, NULL, sizes, 4, 1.0, NULL, ewb, &es), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_new_sizes_in(NULL, k, NULL, NULL, sizes, 4, 1.0, sizes, ewb, &es), COAG_NULL_PARAMETER);
    CHECK(es == NULL, "no sim written on error");
    /* the readers of other kinds of sim refuse, outputs untouched */
    EXPECT(coag_sim_engine(s, &name), COAG_UNSUPPORTED);
    EXPECT(coag_sim_observable(s, "energy", &d), COAG_UNSUPPORTED);
    EXPECT(coag_sim_observable(s, NULL, &d), COAG_NULL_PARAMETER);
    {
        uint64_t vs[4];
        double vv[12];
        size_t w = 77;
        EXPECT(coag_sim_velocities(s, vs, vv, 4), COAG_UNSUPPORTED);
        EXPECT(coag_sim_size_values(s, "temperature", vs, vv, 4, &w), COAG_UNSUPPORTED);
        CHECK(w == 77 && d == -7.0 && strcmp(name, "mfa") == 0, "output written on error");
    }
    coag_sim_free(s);
    s = NULL;

    uint64_t counts[2] = {0, 0};
    /* no particles: a valid, empty system (issue 14) */
    OK(coag_sim_new_counts("lowrank", k, NULL, NULL, counts, 2, 1.0, &s));
    coag_sim_free(s);
    OK(coag_sim_new_counts("lowrank", k, NULL, NULL, NULL, 0, 1.0, &s));
    coag_sim_free(s);
    s = NULL;
    counts[0] = 100;
    EXPECT(coag_sim_new_counts("lowrank", k, NULL, NULL, NULL, 2, 100.0, &s), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_new_counts("no-such-scheme", k, NULL, NULL, counts, 2, 100.0, &s), COAG_INVALID_ARGUMENT);
    bad.rank = 0; /* a user kernel without sup cannot do acceptance-rejection */
    coag_kernel *nk;
    OK(coag_kernel_new_user(&bad, &nk));
    EXPECT(coag_sim_new_counts("rejection", nk, NULL, NULL, counts, 2, 100.0, &s), COAG_UNSUPPORTED);
    /* ... nor low-rank MC without factors */
    EXPECT(coag_sim_new_counts("lowrank", nk, NULL, NULL, counts, 2, 100.0, &s), COAG_UNSUPPORTED);
    EXPECT(coag_sim_new_counts("lowrank", k, NULL, NULL, counts, 2, NAN, &s), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_new_counts("lowrank", k, NULL, NULL, counts, 2, 0.0, &s), COAG_INVALID_ARGUMENT);
    {
        /* fragmentation for a scheme that only coagulates */
        coag_fragmentation *bf;
        OK(coag_fragmentation_new_binary_uniform(1.0, &bf));
        EXPECT(coag_sim_new_counts("lowrank", k, bf, NULL, counts, 2, 100.0, &s), COAG_UNSUPPORTED);
        coag_fragmentation_free(bf);
    }
    CHECK(s == NULL, "no sim written on error");

    /* a working sim, then every misuse on it */
    coag_options *lo = options_new();
    OK(coag_options_set_count(lo, "size-limit", 64));
    OK(coag_sim_new_counts("lowrank", k, NULL, lo, counts, 2, 100.0, &s));
    coag_options_free(lo);
    EXPECT(coag_sim_advance_to(NULL, 1.0, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_advance_to(s, NAN, NULL), COAG_INVALID_ARGUMENT);
    {
        /* a report without its size is refused before the sim moves */
        coag_step_report rep = {0};
        EXPECT(coag_sim_advance_to(s, 0.1, &rep), COAG_INVALID_ARGUMENT);
        OK(coag_sim_time(s, &d));
        CHECK(d == 0.0, "sim unchanged by a refused report: t = %g", d);
        EXPECT(coag_sim_totals(s, &rep), COAG_INVALID_ARGUMENT);
        EXPECT(coag_sim_totals(s, NULL), COAG_NULL_PARAMETER);
        EXPECT(coag_step_report_init(NULL, sizeof rep), COAG_NULL_PARAMETER);
        EXPECT(coag_step_report_init(&rep, 8), COAG_INVALID_ARGUMENT); /* below the first version */
        {
            /* a caller with a larger (newer) report: the known fields are written, nothing past */
            struct {
                coag_step_report r;
                uint64_t extra;
            } big;
            memset(&big, 0xab, sizeof big);
            big.r.struct_size = sizeof big;
            OK(coag_sim_advance_to(s, 0.05, &big.r));
            CHECK(big.r.time == 0.05 && big.extra == 0xababababababababull, "newer report: known fields only");
        }
        OK(coag_step_report_init(&rep, sizeof rep));
        CHECK(rep.struct_size == sizeof rep && rep.events == 0, "report init");
        OK(coag_sim_scheme(s, &name));
        CHECK(strcmp(name, "lowrank") == 0, "scheme %s", name);
    }
    OK(coag_sim_advance_to(s, 0.5, NULL));
    EXPECT(coag_sim_advance_to(s, 0.25, NULL), COAG_TIME_BACKWARDS);
    OK(coag_sim_time(s, &d));
    CHECK(d == 0.5, "time kept after failures: %g", d);
    EXPECT(coag_sim_time(s, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_moment(s, NAN, &d), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_moment(NULL, 1.0, &d), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_concentration(s, NAN, 2.0, &d), COAG_INVALID_ARGUMENT);
    /* issue 14: C(5, 1) returned -0.0, M_{1e6} inf with COAG_OK */
    d = 42.0;
    EXPECT(coag_sim_concentration(s, 5.0, 1.0, &d), COAG_INVALID_ARGUMENT);
    CHECK(d == 42.0, "output untouched on error");
    OK(coag_sim_concentration(s, 1e9, 1e9, &d));
    CHECK(d == 0.0 && !signbit(d), "an empty range is +0: %g", d);
    {
        /* half-open size classes (issue 40): adjacent classes add up to the whole */
        const double edges[4] = {1.0, 2.0, 4.0, INFINITY}, bad[3] = {1.0, 1.0, 2.0};
        const double nan_edges[2] = {NAN, 1.0};
        double cls[3] = {-1.0, -1.0, -1.0}, whole;
        OK(coag_sim_class_concentrations(s, edges, 4, cls));
        OK(coag_sim_concentration(s, 1.0, 1e300, &whole));
        CHECK(fabs(cls[0] + cls[1] + cls[2] - whole) <= 1e-12 * whole, "classes add up");
        EXPECT(coag_sim_class_concentrations(s, bad, 3, cls), COAG_INVALID_ARGUMENT);
        EXPECT(coag_sim_class_concentrations(s, nan_edges, 2, cls), COAG_INVALID_ARGUMENT);
        EXPECT(coag_sim_class_concentrations(s, edges, 1, cls), COAG_INVALID_ARGUMENT);
        EXPECT(coag_sim_class_concentrations(s, NULL, 4, cls), COAG_NULL_PARAMETER);
        EXPECT(coag_sim_class_concentrations(s, edges, 4, NULL), COAG_NULL_PARAMETER);
        cls[0] = 42.0;
        EXPECT(coag_sim_class_concentrations(s, bad, 3, cls), COAG_INVALID_ARGUMENT);
        CHECK(cls[0] == 42.0, "output untouched on error");
        {
            double both[5] = {1.0, 2.0, 4.0, 8.0, 0.0};
            EXPECT(coag_sim_class_concentrations(s, both, 4, both + 1), COAG_INVALID_ARGUMENT);
            CHECK(both[1] == 2.0, "overlapping output untouched");
        }
    }
    EXPECT(coag_sim_moment(s, 1e6, &d), COAG_CAPACITY);
    OK(coag_sim_moment(s, 2.0, &d));
    EXPECT(coag_sim_get_sizes(s, sizes, 4), COAG_UNSUPPORTED); /* not a sim over sizes */
    EXPECT(coag_sim_set_sizes(s, sizes, 4), COAG_UNSUPPORTED);
    EXPECT(coag_sim_set_dt(s, 0.1), COAG_UNSUPPORTED);
    EXPECT(coag_sim_set_fragmentation(s, NULL), COAG_UNSUPPORTED);
    EXPECT(coag_sim_set_mass(s, 2.0), COAG_UNSUPPORTED); /* its mass is its counts */
    OK(coag_sim_state_len(s, &z));
    uint64_t one[1];
    EXPECT(coag_sim_get_counts(s, one, 1, &d), z > 1 ? COAG_BUFFER_TOO_SMALL : COAG_OK);
    EXPECT(coag_sim_get_counts(s, NULL, 0, &d), z > 0 ? COAG_BUFFER_TOO_SMALL : COAG_OK);
    {
        /* pairs: too small, overlapping, NULL with a length */
        size_t occ = 0, w = 77;
        OK(coag_sim_occupied(s, &occ));
        uint64_t ps[128], pc[128];
        if (occ > 0) EXPECT(coag_sim_get_pairs(s, ps, pc, occ - 1, NULL, &w), COAG_BUFFER_TOO_SMALL);
        EXPECT(coag_sim_get_pairs(s, ps, ps + 1, occ, NULL, &w), occ > 1 ? COAG_INVALID_ARGUMENT : COAG_OK);
        CHECK(w == 77 || occ <= 1, "written on error");
        EXPECT(coag_sim_get_pairs(s, NULL, pc, 128, NULL, &w), COAG_NULL_PARAMETER);
        EXPECT(coag_sim_set_pairs(s, NULL, pc, 2, 1.0), COAG_NULL_PARAMETER);
        uint64_t zs[1] = {0}, zc[1] = {1};
        EXPECT(coag_sim_set_pairs(s, zs, zc, 1, 1.0), COAG_INVALID_ARGUMENT); /* size 0 */
    }
    EXPECT(coag_sim_set_counts(s, counts, 2, -1.0), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_counts(s, NULL, 2, 1.0), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_set_kernel(s, NULL), COAG_NULL_PARAMETER);
    coag_kernel *bk = KERNEL0("brownian"); /* rank 2 into a rank-1 low-rank sim */
    EXPECT(coag_sim_set_kernel(s, bk), COAG_UNSUPPORTED);
    coag_kernel_free(bk);
    bk = KERNEL0("hard-spheres"); /* a gas into a coagulation sim */
    EXPECT(coag_sim_set_kernel(s, bk), COAG_UNSUPPORTED);
    coag_kernel_free(bk);
    EXPECT(coag_sim_set_time(s, NAN), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_work_limit(NULL, 1), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_set_cancel_callback(NULL, NULL, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_set_rng_callback(NULL, NULL, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_reseed(NULL, 1, 2), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_clone(s, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_clone(NULL, &es), COAG_NULL_PARAMETER);
    CHECK(es == NULL, "no clone written on error");
    OK(coag_sim_time(s, &d));
    CHECK(d == 0.5, "time kept after failures: %g", d);
    /* the size limit of 64 is reached: a capacity error, and the sim still works */
    int st = COAG_OK;
    double t = 0.5;
    while (st == COAG_OK && t < 1e6) {
        t *= 2.0;
        st = coag_sim_advance_to(s, t, NULL);
    }
    CHECK(st == COAG_CAPACITY, "size limit reached: %s", coag_status_name(st));
    OK(coag_sim_particle_count(s, &u));
    CHECK(u >= 1, "still usable after the failure");
    /* checkpoints: sizes, truncation, garbage */
    size_t need;
    OK(coag_sim_checkpoint_size(s, &need));
    EXPECT(coag_sim_checkpoint_size(s, NULL), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_checkpoint_size(NULL, &z), COAG_NULL_PARAMETER);
    uint8_t *buf = malloc(need);
    EXPECT(coag_sim_checkpoint(s, buf, need / 2, &z), COAG_BUFFER_TOO_SMALL);
    EXPECT(coag_sim_checkpoint(s, NULL, need, &z), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_checkpoint(NULL, buf, need, &z), COAG_NULL_PARAMETER);
    OK(coag_sim_checkpoint(s, buf, need, &z));
    EXPECT(coag_sim_restore(s, buf, need / 2), COAG_BAD_CHECKPOINT);
    EXPECT(coag_sim_restore(NULL, buf, need), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_restore(s, NULL, need), COAG_NULL_PARAMETER);
    buf[40] ^= 0xff;
    int r = coag_sim_restore(s, buf, need);
    CHECK(r == COAG_BAD_CHECKPOINT || r == COAG_OK, "garbage is refused or harmless: %s", coag_status_name(r));
    memset(buf, 0, need);
    EXPECT(coag_sim_restore(s, buf, need), COAG_BAD_CHECKPOINT);
    EXPECT(coag_sim_restore(s, NULL, 0), COAG_BAD_CHECKPOINT);
    free(buf);
    OK(coag_sim_particle_count(s, &u));
    coag_sim_free(s);

    /* a kernel that turns NaN mid-run: INVALID_RATE, then the sim is still usable */
    coag_user_kernel nk2 = {nan_kernel, NULL, 0, NULL, 0, NULL, NULL};
    coag_kernel *nanf;
    OK(coag_kernel_new_user(&nk2, &nanf));
    mo = options_new();
    OK(coag_options_set_real(mo, "dt", 0.1));
    double init[64];
    for (int i = 0; i < 64; i++) init[i] = 1.0;
    OK(coag_sim_new_sizes("massflow", nanf, NULL, mo, init, 64, 1.0, &s));
    coag_options_free(mo);
    st = COAG_OK;
    t = 0.0;
    while (st == COAG_OK && t < 100.0) {
        t += 0.1;
        st = coag_sim_advance_to(s, t, NULL);
    }
    CHECK(st == COAG_INVALID_RATE, "NaN rate reported: %s", coag_status_name(st));
    double before, after;
    OK(coag_sim_moment(s, 2.0, &before));
    EXPECT(coag_sim_advance_to(s, t + 1.0, NULL), COAG_INVALID_RATE);
    OK(coag_sim_moment(s, 2.0, &after));
    CHECK(before == after, "state unchanged by the failed step");
    OK(coag_sim_set_kernel(s, k)); /* repair with a sane kernel and carry on */
    OK(coag_sim_advance_to(s, t + 1.0, NULL));
    double got[64];
    EXPECT(coag_sim_get_sizes(s, got, 63), COAG_BUFFER_TOO_SMALL);
    EXPECT(coag_sim_get_sizes(s, NULL, 64), COAG_NULL_PARAMETER);
    EXPECT(coag_sim_set_sizes(s, init, 63), COAG_BUFFER_TOO_SMALL);
    init[5] = NAN;
    EXPECT(coag_sim_set_sizes(s, init, 64), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_dt(s, -1.0), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_set_mass(s, 0.0), COAG_INVALID_ARGUMENT);
    EXPECT(coag_sim_get_counts(s, &u, 1, NULL), COAG_UNSUPPORTED);
    EXPECT(coag_sim_set_counts(s, &u, 1, 1.0), COAG_UNSUPPORTED);
    EXPECT(coag_sim_engine(s, &name), COAG_UNSUPPORTED);
    OK(coag_sim_moment(s, 2.0, &after));
    CHECK(isfinite(after) && after > 0.0, "still usable: M2 %g", after);
    coag_sim_free(s);
    coag_kernel_free(nanf);
    coag_kernel_free(nk);

    /* frees of NULL are no-ops */
    coag_sim_free(NULL);
    coag_kernel_free(NULL);
    coag_fragmentation_free(NULL);
    coag_options_free(NULL);
    coag_kernel_free(k);
    EXPECT(coag_exact_moment(COAG_EXACT_ADDITIVE, 9, 1.0, &d), COAG_UNSUPPORTED);
    EXPECT(coag_exact_density(COAG_EXACT_COAG_FRAG, 1, 1.0, &d), COAG_UNSUPPORTED);
    EXPECT(coag_exact_moment(COAG_EXACT_ADDITIVE, 1, 1.0, NULL), COAG_NULL_PARAMETER);
    return finish("test_misuse");
}
