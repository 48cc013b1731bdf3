// C++ client of libcoagula through include/coagula.hpp: RAII, exceptions, and the
// constant-kernel exact solution (32 replicas, 6.07 standard errors: Student t_31 at the suite's false-alarm rate 1e-6).
#include <cmath>
#include <cstdio>
#include <vector>

#include "coagula.hpp"

static int failures = 0, checks = 0;
#define CHECK(c, ...)                                              \
    do {                                                           \
        ++checks;                                                  \
        if (!(c)) {                                                \
            ++failures;                                            \
            std::fprintf(stderr, "%s:%d: %s: ", __FILE__, __LINE__, #c); \
            std::fprintf(stderr, __VA_ARGS__);                     \
            std::fprintf(stderr, "\n");                            \
        }                                                          \
    } while (0)

int main() {
    auto k = coagula::Kernel::constant(1.0);
    CHECK(k.rate(2.0, 3.0) == 1.0, "rate");
    double sum = 0, sum2 = 0;
    const int reps = 32;
    for (int r = 0; r < reps; ++r) {
        auto c = coagula::counts_default_config();
        c.seed = 31 + r;
        auto sim = coagula::Sim::counts(c, k, {1u << 13});
        if (r == 0) CHECK(sim.method() == COAG_METHOD_LOWRANK, "default method: bucketed low-rank");
        if (r == 0) CHECK(sim.bucket_mode() == COAG_BUCKET_COUNTED, "8192 particles: the counted engine");
        for (int h = 1; h <= 10; ++h) sim.advance_to(0.2 * h);
        double m0 = sim.moment(0.0);
        sum += m0;
        sum2 += m0 * m0;
    }
    double mean = sum / reps, se = std::sqrt((sum2 / reps - mean * mean) / (reps - 1));
    double exact = 0.0;
    coagula::check(coag_exact_moment(COAG_EXACT_CONSTANT, 0, 2.0, &exact));
    CHECK(std::fabs(mean - exact) < 6.072 * se, "M0 %g ± %g vs %g", mean, se, exact);

    // mass flow with fragmentation, and a checkpoint round trip
    auto f = coagula::Fragmentation::binary_uniform(1.0);
    auto mc = coagula::massflow_default_config();
    auto sim = coagula::Sim::massflow(mc, k, &f, std::vector<double>(1024, 1.0));
    sim.advance_to(0.5);
    auto ck = sim.checkpoint();
    sim.advance_to(1.0);
    auto other = coagula::Sim::massflow(mc, k, &f, std::vector<double>(1024, 1.0));
    other.restore(ck);
    other.advance_to(1.0);
    CHECK(sim.sizes() == other.sizes(), "checkpoint round trip");
    double e2 = 0.0;
    coagula::check(coag_exact_moment(COAG_EXACT_COAG_FRAG, 2, 1.0, &e2));
    CHECK(std::fabs(sim.moment(2.0) - e2) < 0.02, "M2(1) %g vs %g", sim.moment(2.0), e2);

    // errors become exceptions carrying the code
    bool thrown = false;
    try {
        coagula::Kernel::constant(-1.0);
    } catch (const coagula::Error &e) {
        thrown = e.code() == COAG_INVALID_ARGUMENT && std::string(e.what()).find("k0") != std::string::npos;
    }
    CHECK(thrown, "invalid kernel throws");
    thrown = false;
    try {
        sim.advance_to(0.1);
    } catch (const coagula::Error &e) {
        thrown = e.code() == COAG_TIME_BACKWARDS;
    }
    CHECK(thrown, "time backwards throws");

    // every other function of the C ABI through the wrapper
    CHECK(!coagula::version().empty() && coagula::status_name(COAG_INTERRUPTED) == "COAG_INTERRUPTED", "names");
    CHECK(coagula::exact_moment(COAG_EXACT_CONSTANT, 0, 2.0) == 0.5, "exact moment");
    CHECK(std::fabs(coagula::exact_density(COAG_EXACT_CONSTANT, 1, 2.0) - 0.25) < 1e-15, "exact density");
    CHECK(coagula::massflow_workspace_size(1024) == 6 * 1024 * sizeof(double), "workspace size");
    std::vector<double> ws(6 * 1024);
    {
        auto in = coagula::Sim::massflow_in(mc, k, nullptr, std::vector<double>(1024, 1.0), ws.data(),
                                            ws.size() * sizeof(double));
        in.set_dt(0.05);
        in.set_fragmentation(&f);
        in.set_mass(2.0);
        in.advance_to(0.5);
        auto cfg = in.massflow_config();
        CHECK(cfg.dt == 0.05 && cfg.mass == 2.0, "config read back");
        CHECK(std::fabs(in.moment(1.0) - 2.0) < 1e-9, "M1 = mass %g", in.moment(1.0));
        in.set_time(3.0);
        CHECK(in.time() == 3.0, "set_time");
        CHECK(in.totals().events > 0 && in.occupied() == 1024, "totals, occupied");
        in.set_fragmentation(nullptr);
        in.set_sizes(std::vector<double>(1024, 2.0));
        CHECK(in.sizes()[0] == 2.0, "set_sizes");
    }
    {
        // the mass flow algorithm, event-driven, with gelation: the multiplicative
        // kernel's gel mass at t = 2 is 1 - 1/t = 0.5 (one run of 4096 particles with
        // b_N = N: its standard deviation is about 0.01)
        coagula::Kernel km = coagula::Kernel::multiplicative();
        auto ec = coagula::eventflow_default_config();
        ec.truncation = 4096;
        ec.seed = 3;
        auto e = coagula::Sim::eventflow(ec, km, nullptr, std::vector<double>(4096, 1.0));
        e.advance_to(2.0);
        CHECK(std::fabs(e.gel_mass() - 0.5) < 0.06, "MFA gel mass %g", e.gel_mass());
        CHECK(e.eventflow_config().truncation == 4096, "eventflow config read back");
        // the same run in caller-owned memory, bit for bit
        std::vector<double> ws(coagula::eventflow_workspace_size(ec, nullptr, 4096) / sizeof(double));
        auto in = coagula::Sim::eventflow_in(ec, km, nullptr, std::vector<double>(4096, 1.0), ws.data(),
                                             ws.size() * sizeof(double));
        in.advance_to(2.0);
        CHECK(in.sizes() == e.sizes(), "eventflow in a workspace: the sizes differ");
        // direct simulation: a clone continues as the original
        ec.method = COAG_EVENTFLOW_DSA;
        ec.truncation = 0;
        auto d = coagula::Sim::eventflow(ec, km, nullptr, std::vector<double>(512, 1.0));
        d.advance_to(0.5);
        auto dc = d.clone();
        d.advance_to(1.5);
        dc.advance_to(1.5);
        CHECK(d.sizes() == dc.sizes() && d.totals().events > 0, "DSA clone differs");
    }
    auto cc = coagula::counts_default_config();
    cc.method = COAG_METHOD_INVERSE;
    auto a = coagula::Sim::counts(cc, k, {2000, 10});
    a.reseed(5, 1);
    a.set_work_limit(300);
    coag_step_report rep;
    int stops = 0;
    while (!a.advance_within(1.0, &rep)) ++stops;
    CHECK(stops > 0 && a.time() == 1.0, "work limit: %d stops", stops);
    a.set_work_limit(0);
    auto b = a.clone();
    a.advance_to(2.0);
    b.advance_to(2.0);
    CHECK(a.counts() == b.counts() && a.counts_config().method == COAG_METHOD_INVERSE, "clone");
    std::vector<std::uint64_t> ps, pc;
    double v = 0;
    a.pairs(ps, pc, &v);
    CHECK(!ps.empty() && ps.size() == a.occupied() && v > 0, "pairs");
    b.set_pairs(ps, pc, v);
    CHECK(b.counts() == a.counts(), "set_pairs");
    b.set_counts({}, 1.0);
    CHECK(b.particle_count() == 0 && b.state_len() == 0, "an empty system");
    b.set_kernel(coagula::Kernel::additive());
    struct Ctx { std::uint64_t x = 1; } ctx;
    a.set_rng_callback(
        [](void *p) -> std::uint64_t {
            auto *c = static_cast<Ctx *>(p);
            c->x ^= c->x << 13;
            c->x ^= c->x >> 7;
            c->x ^= c->x << 17;
            return c->x;
        },
        &ctx);
    a.advance_to(2.5);
    a.set_rng_callback(nullptr, nullptr);
    int polls = 0;
    a.set_cancel_callback([](void *p) -> std::int32_t { return ++*static_cast<int *>(p) >= 1; }, &polls);
    a.set_kernel(coagula::Kernel::constant(1.0));
    CHECK(a.gel_mass() > 0 && a.concentration(1.0, 1.0) >= 0, "observables");
    // temperature-dependent MC: the model family's closed form over 32 replicas
    // (Student t, 6.07 SE); a checkpoint continues bit for bit
    {
        auto ex = coagula::thermal_model_exact(1.0, 1.0, 1.0, 1.0, 4.0);
        double s1 = 0, s2 = 0;
        const int reps = 32;
        for (int r = 0; r < reps; ++r) {
            auto c = coagula::thermal_default_config();
            c.kernel = COAG_THERMAL_MODEL;
            c.model_gamma = 1.0;
            c.engine = r % 2 ? COAG_THERMAL_REJECTION : COAG_THERMAL_LOWRANK;
            c.seed = 42;
            c.stream = static_cast<std::uint64_t>(r);
            auto t = coagula::Thermal::make(c, {20000}, {1.0}, 20000.0);
            t.advance_to(4.0);
            double tm = t.mean_temperature();
            s1 += tm;
            s2 += tm * tm;
        }
        double mean = s1 / reps, se = std::sqrt((s2 / reps - mean * mean) / (reps - 1));
        CHECK(std::fabs(mean - ex.second) < 6.07 * se, "thermal mean T %g vs %g +- %g", mean, ex.second, se);
        auto c = coagula::thermal_default_config();
        auto a = coagula::Thermal::make(c, {3000, 200}, {1.0, 1.5}, 30000.0);
        auto b = coagula::Thermal::make(c, {3000, 200}, {1.0, 1.5}, 30000.0);
        a.advance_to(20.0);
        auto cp = a.checkpoint();
        a.advance_to(40.0);
        b.restore(cp);
        b.advance_to(40.0);
        CHECK(a.counts() == b.counts() && a.temperatures() == b.temperatures() && a.time() == b.time(),
              "thermal bits");
        CHECK(a.particles() > 0 && a.volume() == 30000.0 && a.moment(1.0) > 0 && a.energy() > 0, "thermal obs");
    }
    // DSMC: elastic collisions conserve momentum and energy; a checkpoint continues
    // bit for bit
    {
        auto c = coagula::dsmc_default_config();
        c.restitution = 1.0;
        auto a = coagula::Dsmc::maxwellian(c, {300, 100}, {1.0, 2.0}, 4000.0);
        auto b = coagula::Dsmc::make(c, {1, 2}, {1.0, 0.0, 0.0, -1.0, 0.0, 0.0}, 10.0);
        auto p0 = a.momentum();
        double e0 = a.energy();
        a.advance_to(10.0);
        auto cp = a.checkpoint();
        auto p1 = a.momentum();
        CHECK(std::fabs(p1[0] - p0[0]) < 1e-9 && std::fabs(a.energy() - e0) < 1e-12 * e0, "dsmc conservation");
        a.advance_to(20.0);
        auto s1 = a.state();
        auto a2 = coagula::Dsmc::maxwellian(c, {300, 100}, {1.0, 2.0}, 4000.0);
        a2.restore(cp);
        a2.advance_to(20.0);
        CHECK(a2.state() == s1 && a2.time() == 20.0 && a2.particles() == 400 && a2.volume() == 4000.0,
              "dsmc bits");
        CHECK(a.mean_temperature() > 0 && b.particles() == 2, "dsmc obs");
    }
    // Langevin batches: b = 0 outside the unit ball keeps E|U|^2 = |u0|^2 + 3 T
    // (4.89 SE), caller memory and a checkpoint continue bit for bit, errors throw
    {
        auto c = coagula::langevin_default_config();
        c.dim = 3;
        c.radius = 1.0;
        c.dt = 0.02;
        auto b = coagula::Langevin::make(c, 20000, {1.2, 0.0, 0.0}, {-2.0, 0.0, 0.0}, 11);
        auto r = b.advance_to(1.0);
        CHECK(r.bounces > 1000 && b.time() == 1.0 && b.dim() == 3 && b.size() == 20000, "langevin run");
        auto e = b.mean([](const double *, const double *u, std::size_t d, void *) {
            double s = 0;
            for (std::size_t k = 0; k < d; ++k) s += u[k] * u[k];
            return s;
        });
        CHECK(std::fabs(e.mean - 7.0) < 4.89 * e.std_error, "E|U|^2 %g +- %g", e.mean, e.std_error);
        CHECK(b.mean().mean > 0.5 && b.hits().size() == 20000 && b.first_hits().size() == 20000, "hits");
        auto p = coagula::langevin_default_config();
        p.drift = COAG_DRIFT_MAFTEI2016;
        p.dt = 0.1;
        p.period = 1.0;
        std::vector<double> ws(coagula::langevin_workspace_size(p, 500) / sizeof(double));
        auto own = coagula::Langevin::make(p, 500, {0.5}, {-1.5}, 9);
        auto mine = coagula::Langevin::make_in(p, 500, {0.5}, {-1.5}, 9, 0, ws.data(), ws.size() * sizeof(double));
        own.advance_to(1.6);
        mine.advance_to(1.6);
        auto cp = mine.checkpoint();
        own.advance_to(3.2);
        mine.advance_to(3.2);
        mine.restore(cp);
        mine.advance_to(3.2);
        CHECK(own.positions() == mine.positions() && own.velocities() == mine.velocities(), "langevin bits");
        bool threw = false;
        try {
            own.advance_to(1.0);
        } catch (const coagula::Error &err) {
            threw = err.code() == COAG_TIME_BACKWARDS;
        }
        CHECK(threw, "time backwards throws");
        coag_first_hits fh{};
        fh.struct_size = sizeof fh;
        fh.dim = 2;
        fh.radius = 0.5;
        fh.outer = 10.0;
        fh.from = 0.4;
        fh.to = 1.0;
        fh.dt = 0.1;
        fh.velocity_sd = 1.0;
        fh.trajectories = 50000;
        fh.drift = COAG_DRIFT_ZERO;
        auto k2 = coagula::first_hit_kernel(fh, 3);
        double exact = 2.0 * 0.5 * std::sqrt(std::acos(-1.0) / 2.0);
        CHECK(std::fabs(k2.mean - exact) < 4.89 * k2.std_error, "2-D free-flight kernel %g +- %g", k2.mean,
              k2.std_error);
    }
    std::printf("test_cpp: %d passed, %d failed\n", checks - failures, failures);
    return failures ? 1 : 0;
}
