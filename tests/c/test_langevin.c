/* The Langevin batches of the C ABI (Maftei et al. 2016): exact references (the velocity
 * variance kept by specular reflections, the scheme's own moments away from the wall,
 * the free-flight collision kernel), a C drift callback against the built-in friction
 * bit for bit, caller memory, checkpoints, and refusals that leave the batch unchanged.
 * Statistical checks use 4.89 standard errors (a two-sided 1e-6 false alarm each with
 * thousands of trajectories). */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "check.h"

#define Z 4.89

static int cancel_now(void *ud) {
    (void)ud;
    return 1;
}

static int friction_cb(double t, const double *x, const double *u, size_t dim, double *out, void *ud) {
    (void)t;
    (void)x;
    double rate = *(const double *)ud;
    for (size_t k = 0; k < dim; k++) out[k] = -rate * u[k];
    return 0;
}

static int failing_cb(double t, const double *x, const double *u, size_t dim, double *out, void *ud) {
    (void)x;
    (void)u;
    (void)ud;
    for (size_t k = 0; k < dim; k++) out[k] = 0.0;
    return t > 0.45 ? 7 : 0; /* fails after t = 0.45 */
}

static double u_squared(const double *x, const double *u, size_t dim, void *ud) {
    (void)x;
    (void)ud;
    double s = 0.0;
    for (size_t k = 0; k < dim; k++) s += u[k] * u[k];
    return s;
}

static double position(const double *x, const double *u, size_t dim, void *ud) {
    (void)u;
    (void)dim;
    return x[0] - *(const double *)ud;
}

int main(void) {
    /* 1. b = 0 outside the unit ball in 3-D: reflections are isometries, so
     *    E |U_T|^2 = |u0|^2 + 3 sigma^2 T exactly. */
    coag_langevin_config c;
    OK(coag_langevin_default_config(&c, sizeof c));
    c.dim = 3;
    c.radius = 1.0;
    c.dt = 0.02;
    c.sigma = 1.0;
    double x0[3] = {1.2, 0.0, 0.0}, u0[3] = {-2.0, 0.0, 0.0};
    coag_langevin *b = NULL;
    OK(coag_langevin_new(&c, 20000, x0, u0, 11, 0, &b));
    coag_step_report r;
    OK(coag_step_report_init(&r, sizeof r));
    OK(coag_langevin_advance_to(b, 1.0, &r));
    CHECK(r.bounces > 1000, "bounces %llu", (unsigned long long)r.bounces);
    double m, se, hits_m, hits_se;
    OK(coag_langevin_mean(b, u_squared, NULL, &m, &se, NULL));
    CHECK(fabs(m - 7.0) < Z * se, "E|U|^2 = %g +- %g, exact 7", m, se);
    OK(coag_langevin_mean(b, NULL, NULL, &hits_m, &hits_se, NULL));
    CHECK(hits_m > 0.5, "hits per trajectory %g", hits_m);
    double t;
    size_t dim;
    uint64_t n;
    OK(coag_langevin_info(b, &t, &dim, &n));
    CHECK(t == 1.0 && dim == 3 && n == 20000, "info %g %zu %llu", t, dim, (unsigned long long)n);
    coag_langevin_free(b);

    /* 2. Friction far from the wall: the scheme's own mean x_T (x' = x + h u,
     *    u' = (1 - g h) u + s sqrt(h) Z). The C callback gives the built-in's bits. */
    double g = 0.7, h = 0.05;
    double mx = 0.0, mu = 0.5;
    for (int i = 0; i < 40; i++) {
        mx += h * mu;
        mu *= 1.0 - g * h;
    }
    OK(coag_langevin_default_config(&c, sizeof c));
    c.dt = h;
    c.sigma = 1.3;
    c.drift = COAG_DRIFT_FRICTION;
    c.friction_rate = g;
    double far = 1e6, xs = far, us = 0.5;
    coag_langevin *fb = NULL, *cb = NULL;
    OK(coag_langevin_new(&c, 20000, &xs, &us, 5, 0, &fb));
    OK(coag_langevin_advance_to(fb, 2.0, NULL));
    OK(coag_langevin_mean(fb, position, &far, &m, &se, NULL));
    CHECK(fabs(m - mx) < Z * se, "E x = %g +- %g, exact %g", m, se, mx);
    c.drift = COAG_DRIFT_CALLBACK;
    c.drift_fn = friction_cb;
    c.drift_user_data = &g;
    OK(coag_langevin_new(&c, 20000, &xs, &us, 5, 0, &cb));
    OK(coag_langevin_advance_to(cb, 2.0, NULL));
    static double xa[20000], xb[20000], ua[20000], ub[20000];
    OK(coag_langevin_state(fb, xa, ua, NULL, NULL, 20000));
    OK(coag_langevin_state(cb, xb, ub, NULL, NULL, 20000));
    CHECK(memcmp(xa, xb, sizeof xa) == 0 && memcmp(ua, ub, sizeof ua) == 0, "callback = built-in");
    coag_langevin_free(fb);
    coag_langevin_free(cb);

    /* 3. The paper's problem in caller memory equals the library's, and a checkpoint
     *    taken at t = 1.6 and restored continues bit for bit. */
    OK(coag_langevin_default_config(&c, sizeof c));
    c.drift = COAG_DRIFT_MAFTEI2016;
    c.dt = 0.1;
    c.period = 1.0;
    c.bound_kind = COAG_BOUND_REFLECT;
    c.bound = 10.0;
    double px = 0.5, pu = -1.5;
    size_t bytes = 0;
    OK(coag_langevin_workspace_size(&c, 1000, &bytes));
    double *ws = malloc(bytes);
    coag_langevin *own = NULL, *mine = NULL;
    OK(coag_langevin_new(&c, 1000, &px, &pu, 9, 0, &own));
    OK(coag_langevin_new_in(&c, 1000, &px, &pu, 9, 0, ws, bytes, &mine));
    /* (found by review) a count whose workspace bytes overflow is refused, not run in
     * the small buffer; arrays overlapping the workspace are refused */
    coag_langevin *huge = NULL;
    CHECK(coag_langevin_new_in(&c, (uint64_t)1 << 58, &px, &pu, 9, 0, ws, bytes, &huge) != COAG_OK && huge == NULL,
          "workspace bytes overflow refused");
    EXPECT(coag_langevin_state(mine, ws, NULL, NULL, NULL, 1000), COAG_INVALID_ARGUMENT);
    EXPECT(coag_langevin_save(mine, (unsigned char *)ws, 64, NULL), COAG_INVALID_ARGUMENT);
    OK(coag_langevin_advance_to(own, 1.6, NULL));
    OK(coag_langevin_advance_to(mine, 1.6, NULL));
    size_t need = 0, written = 0;
    OK(coag_langevin_checkpoint_size(mine, &need));
    unsigned char *cp = malloc(need);
    OK(coag_langevin_save(mine, cp, need, &written));
    OK(coag_langevin_advance_to(own, 3.2, NULL));
    OK(coag_langevin_advance_to(mine, 3.2, NULL));
    OK(coag_langevin_restore(mine, cp, written));
    OK(coag_langevin_advance_to(mine, 3.2, NULL));
    static uint64_t ha[1000], hb[1000];
    OK(coag_langevin_state(own, xa, ua, ha, NULL, 1000));
    OK(coag_langevin_state(mine, xb, ub, hb, NULL, 1000));
    CHECK(memcmp(xa, xb, 1000 * sizeof(double)) == 0 && memcmp(ha, hb, sizeof ha) == 0,
          "caller memory and restore continue bit for bit");
    coag_langevin_free(mine);
    free(ws);
    free(cp);

    /* 4. Refusals leave the batch as it was. */
    double before_x[1000];
    OK(coag_langevin_state(own, before_x, NULL, NULL, NULL, 1000));
    EXPECT(coag_langevin_advance_to(own, 1.0, NULL), COAG_TIME_BACKWARDS);
    EXPECT(coag_langevin_advance_to(own, NAN, NULL), COAG_INVALID_ARGUMENT);
    EXPECT(coag_langevin_state(own, before_x, NULL, NULL, NULL, 999), COAG_BUFFER_TOO_SMALL);
    EXPECT(coag_langevin_restore(own, (const unsigned char *)"garbage", 7), COAG_BAD_CHECKPOINT);
    OK(coag_langevin_state(own, xa, NULL, NULL, NULL, 1000));
    CHECK(memcmp(xa, before_x, sizeof before_x) == 0, "unchanged after refusals");
    coag_langevin_free(own);

    c.drift = COAG_DRIFT_CALLBACK;
    c.drift_fn = failing_cb;
    c.drift_user_data = NULL;
    c.period = 0.0;
    coag_langevin *fail = NULL;
    double one = 1.0, zero = 0.0;
    OK(coag_langevin_new(&c, 50, &one, &zero, 3, 0, &fail));
    OK(coag_langevin_advance_to(fail, 0.3, NULL));
    double fx[50], fx2[50];
    OK(coag_langevin_state(fail, fx, NULL, NULL, NULL, 50));
    EXPECT(coag_langevin_advance_to(fail, 1.0, NULL), COAG_INVALID_RATE);
    OK(coag_langevin_state(fail, fx2, NULL, NULL, NULL, 50));
    OK(coag_langevin_info(fail, &t, NULL, NULL));
    CHECK(t == 0.3 && memcmp(fx, fx2, sizeof fx) == 0, "a failing drift changes nothing");
    coag_langevin_free(fail);

    coag_langevin *nb = NULL;
    OK(coag_langevin_default_config(&c, sizeof c));
    EXPECT(coag_langevin_new(NULL, 10, &one, &zero, 1, 0, &nb), COAG_NULL_PARAMETER);
    EXPECT(coag_langevin_new(&c, 10, NULL, &zero, 1, 0, &nb), COAG_NULL_PARAMETER);
    EXPECT(coag_langevin_new(&c, 0, &one, &zero, 1, 0, &nb), COAG_INVALID_ARGUMENT);
    double neg = -1.0;
    EXPECT(coag_langevin_new(&c, 10, &neg, &zero, 1, 0, &nb), COAG_INVALID_ARGUMENT);
    coag_langevin_config bad = c;
    bad.dt = 0.0;
    EXPECT(coag_langevin_new(&bad, 10, &one, &zero, 1, 0, &nb), COAG_INVALID_ARGUMENT);
    bad = c;
    bad.sigma = -1.0;
    EXPECT(coag_langevin_new(&bad, 10, &one, &zero, 1, 0, &nb), COAG_INVALID_ARGUMENT);
    bad = c;
    bad.dim = 4;
    EXPECT(coag_langevin_new(&bad, 10, &one, &zero, 1, 0, &nb), COAG_INVALID_ARGUMENT);
    bad = c;
    bad.struct_size = 3;
    EXPECT(coag_langevin_new(&bad, 10, &one, &zero, 1, 0, &nb), COAG_INVALID_ARGUMENT);
    bad = c;
    bad.drift = COAG_DRIFT_CALLBACK;
    bad.drift_fn = NULL;
    EXPECT(coag_langevin_new(&bad, 10, &one, &zero, 1, 0, &nb), COAG_NULL_PARAMETER);
    bad = c;
    bad.dim = 3;
    bad.radius = 1.0;
    bad.drift = COAG_DRIFT_ZERO;
    double inside[3] = {0.5, 0.0, 0.0}, v3[3] = {0.0, 0.0, 0.0};
    /* a start inside the absorbing sphere */
    EXPECT(coag_langevin_new(&bad, 10, inside, v3, 1, 0, &nb), COAG_INVALID_ARGUMENT);
    /* the paper's drift is one-dimensional (core's verdict: unsupported) */
    bad.drift = COAG_DRIFT_MAFTEI2016;
    inside[0] = 2.0;
    EXPECT(coag_langevin_new(&bad, 10, inside, v3, 1, 0, &nb), COAG_UNSUPPORTED);
    CHECK(nb == NULL, "no handle written on failure");
    coag_langevin_free(NULL);

    /* 5. The free-flight kernel from first hits: pi R^2 <|v|> = pi R^2 s sqrt(8/pi). */
    coag_first_hits p;
    memset(&p, 0, sizeof p);
    p.struct_size = sizeof p;
    p.dim = 3;
    p.radius = 0.5;
    p.outer = 10.0;
    p.from = 0.4;
    p.to = 1.0;
    p.dt = 0.1;
    p.sigma = 0.0;
    p.velocity_sd = 1.0;
    p.trajectories = 100000;
    p.drift = COAG_DRIFT_ZERO;
    uint64_t hits = 0;
    OK(coag_first_hit_kernel(&p, 7, 0, &m, &se, &hits));
    double pi = acos(-1.0);
    double exact = pi * 0.25 * sqrt(8.0 / pi);
    CHECK(fabs(m - exact) < Z * se, "free-flight kernel %g +- %g, exact %g", m, se, exact);
    CHECK(hits > 100, "hits %llu", (unsigned long long)hits);
    p.outer = 0.4;
    EXPECT(coag_first_hit_kernel(&p, 7, 0, &m, &se, &hits), COAG_INVALID_ARGUMENT);
    /* issue 40: 2^50 trajectories never returned; a work limit or a cancel callback
     * stops them (no estimate), and a caller of the version-1 struct gets no limit */
    p.outer = 10.0;
    p.trajectories = 1ULL << 50;
    p.work_limit = 1000000;
    m = -1.0;
    EXPECT(coag_first_hit_kernel(&p, 7, 0, &m, &se, &hits), COAG_INTERRUPTED);
    CHECK(m == -1.0, "no estimate written when interrupted");
    p.work_limit = 0;
    p.cancel = cancel_now;
    EXPECT(coag_first_hit_kernel(&p, 7, 0, &m, &se, &hits), COAG_INTERRUPTED);
    p.cancel = NULL;
    p.trajectories = 1000;
    p.struct_size = offsetof(coag_first_hits, work_limit);
    OK(coag_first_hit_kernel(&p, 7, 0, &m, &se, &hits));
    p.struct_size = offsetof(coag_first_hits, work_limit) - 1;
    EXPECT(coag_first_hit_kernel(&p, 7, 0, &m, &se, &hits), COAG_INVALID_ARGUMENT);

    return finish("test_langevin");
}
