// C++ client of libcoagula through include/coagula.hpp: RAII, exceptions, the one
// registry (every scheme built through the one Sim handle from the initial state its
// capabilities name, checkpointed, restored and cloned), statistical checks against
// exact solutions (32 replicas, 6.07 standard errors: Student t_31 at the suite's
// false-alarm rate 1e-6), errors as coagula::Error codes, Langevin batches.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "coagula.hpp"

static int failures = 0, checks = 0;
#define CHECK(c, ...)                                                    \
    do {                                                                 \
        ++checks;                                                        \
        if (!(c)) {                                                      \
            ++failures;                                                  \
            std::fprintf(stderr, "%s:%d: %s: ", __FILE__, __LINE__, #c); \
            std::fprintf(stderr, __VA_ARGS__);                           \
            std::fprintf(stderr, "\n");                                  \
        }                                                                \
    } while (0)

namespace {

using coagula::Kernel;
using coagula::Options;
using coagula::SchemeInfo;
using coagula::Sim;

/// The code of the coagula::Error `f` throws (COAG_OK when it throws none), and its
/// message into *msg.
template <class F>
int code_of(F f, std::string *msg = nullptr) {
    try {
        f();
    } catch (const coagula::Error &e) {
        if (msg) *msg = e.what();
        return e.code();
    }
    return COAG_OK;
}

bool contains(const std::string &s, const std::string &part) { return s.find(part) != std::string::npos; }

/// The physics a scheme's model takes.
Kernel kernel_for(const SchemeInfo &s) {
    switch (s.model) {
        case COAG_MODEL_TEMPERATURE: return Kernel::builtin("temperature-closed-form", {1.0, 1.0});
        case COAG_MODEL_GAS: return Kernel::builtin("hard-spheres", {1.0});  // elastic
        default: return Kernel::constant();
    }
}

/// A sim of scheme `s` from the first initial state its capabilities list.
Sim build(const SchemeInfo &s, const Kernel &k, const Options *o) {
    if (s.takes(COAG_INIT_COUNTS)) return Sim::from_counts(s.name, k, {1500, 200, 30}, 2000.0, o);
    if (s.takes(COAG_INIT_SIZES)) return Sim::from_sizes(s.name, k, std::vector<double>(1024, 1.0), 1.0, o);
    if (s.takes(COAG_INIT_TEMPERATURES))
        return Sim::from_temperatures(s.name, k, {1500, 200}, {1.0, 1.5}, 2000.0, o);
    if (s.takes(COAG_INIT_VELOCITIES)) return Sim::from_maxwellian(s.name, k, {300, 100}, {1.0, 2.0}, 400.0, o);
    throw std::logic_error("scheme " + s.name + ": no initial state this test knows");
}

/// The state of a sim as its capabilities describe it, flattened to doubles.
std::vector<double> state_of(const SchemeInfo &s, const Sim &sim) {
    std::vector<double> v;
    if (s.takes(COAG_INIT_SIZES)) return sim.sizes();
    if (s.takes(COAG_INIT_VELOCITIES)) {
        auto p = sim.particles();
        for (std::size_t i = 0; i < p.sizes.size(); ++i) v.push_back(static_cast<double>(p.sizes[i]));
        v.insert(v.end(), p.velocities.begin(), p.velocities.end());
        return v;
    }
    auto p = sim.pairs();
    for (std::size_t i = 0; i < p.sizes.size(); ++i) {
        v.push_back(static_cast<double>(p.sizes[i]));
        v.push_back(static_cast<double>(p.counts[i]));
    }
    if (s.takes(COAG_INIT_TEMPERATURES)) {
        auto t = sim.size_values("temperature");
        v.insert(v.end(), t.values.begin(), t.values.end());
    }
    return v;
}

/// Mean and standard error of `reps` values.
struct Stat {
    double mean, se;
};
Stat stat(const std::vector<double> &x) {
    double s = 0, s2 = 0;
    for (double v : x) s += v;
    double m = s / x.size();
    for (double v : x) s2 += (v - m) * (v - m);
    return {m, std::sqrt(s2 / (x.size() - 1) / x.size())};
}

const double kTolerance = 6.07;  // standard errors: t_31 at a false-alarm rate of 1e-6
const int kReplicas = 32;

void test_tables() {
    CHECK(!coagula::version().empty(), "version");
    CHECK(coagula::status_name(COAG_REENTRANT) == "COAG_REENTRANT", "status name");
    CHECK(coagula::status_name(999) == "COAG_UNKNOWN", "unknown status name");
    auto keys = coagula::option_infos();
    CHECK(keys.size() == coagula::option_count() && !keys.empty(), "option count");
    auto key = [&](const std::string &n) {
        return std::find_if(keys.begin(), keys.end(), [&](const coagula::OptionInfo &k) { return k.name == n; });
    };
    CHECK(key("seed") != keys.end() && key("seed")->kind == COAG_OPTION_COUNT, "seed is a count");
    CHECK(key("dt") != keys.end() && key("dt")->kind == COAG_OPTION_REAL && key("dt")->must_match, "dt");
    CHECK(key("points") != keys.end() && key("points")->kind == COAG_OPTION_NAME, "points");
    auto all = coagula::schemes();
    CHECK(all.size() == coagula::scheme_count() && all.size() >= 5, "%zu schemes", all.size());
    for (const auto &s : all) {
        CHECK(coagula::scheme_find(s.name) == s.index, "find %s", s.name.c_str());
        CHECK(!s.paper.empty() && !s.summary.empty() && s.inits != 0, "%s: described", s.name.c_str());
        for (const auto &o : s.options) CHECK(key(o) != keys.end(), "%s: option %s is a key", s.name.c_str(), o.c_str());
    }
    auto lr = coagula::scheme_info("lowrank");
    CHECK(lr.takes(COAG_INIT_COUNTS) && lr.model == COAG_MODEL_COAGULATION, "lowrank takes counts");
    // every built-in kernel by name; required parameters from a table of valid values
    struct Required {
        const char *name;
        double value;
    } required[] = {{"a", 0.5},           {"gamma", 1.5},     {"temperature", 300.0},
                    {"viscosity", 1.8e-5}, {"density", 1000.0}, {"monomer-diameter", 3e-10}};
    auto b = coagula::builtins();
    CHECK(b.size() == coagula::builtin_count() && !b.empty(), "builtins");
    for (const auto &info : b) {
        std::vector<double> params;
        for (const auto &p : info.params) {
            if (p.has_default) {
                params.push_back(p.default_value);
                continue;
            }
            CHECK(std::isnan(p.default_value), "%s.%s: required, NaN default", info.name.c_str(), p.name.c_str());
            auto r = std::find_if(std::begin(required), std::end(required),
                                  [&](const Required &q) { return p.name == q.name; });
            CHECK(r != std::end(required), "%s: no test value for parameter %s", info.name.c_str(), p.name.c_str());
            params.push_back(r != std::end(required) ? r->value : 1.0);
        }
        std::string msg;
        int code = code_of([&] {
            auto k = Kernel::builtin(info.name, params);
            if (info.family == COAG_FAMILY_COAGULATION)
                CHECK(k.rate(2.0, 3.0) > 0, "%s rate", info.name.c_str());
            else
                CHECK(code_of([&] { k.rate(2.0, 3.0); }) == COAG_UNSUPPORTED, "%s: no K(x, y)", info.name.c_str());
        }, &msg);
        CHECK(code == COAG_OK, "builtin %s: %s", info.name.c_str(), msg.c_str());
    }
    CHECK(Kernel::product(0.5).rate(4.0, 9.0) == 6.0 && Kernel::product(0.5, 2.0).rate(4.0, 9.0) == 12.0, "product");
    CHECK(Kernel::additive(2.0).rate(1.0, 2.0) == 6.0 && Kernel::additive(2.0, 1.0).rate(1.0, 2.0) == 6.0 &&
              Kernel::additive().rate(1.0, 2.0) == 3.0,
          "additive");
    CHECK(Kernel::multiplicative().rate(2.0, 3.0) == 6.0 && Kernel::multiplicative(0.5).rate(2.0, 3.0) == 3.0,
          "multiplicative");
    CHECK(Kernel::constant().rate(2.0, 3.0) == 1.0 && Kernel::constant(3.0).rate(2.0, 3.0) == 3.0, "constant");
}

/// Every scheme of the registry through the one handle: built from the initial state
/// its capabilities name, advanced, checkpointed and restored into a fresh sim (the
/// same continuation), cloned (the same continuation), its observables read.
void test_every_scheme() {
    for (const auto &s : coagula::schemes()) {
        const char *name = s.name.c_str();
        std::string msg;
        int code = code_of([&] {
            Options o;
            o.set("seed", 7 + s.index).set("stream", 3);
            auto k = kernel_for(s);
            auto a = build(s, k, &o);
            CHECK(a.scheme() == s.name, "%s: scheme() is %s", name, a.scheme().c_str());
            a.advance_to(0.5);
            auto cp = a.checkpoint();
            auto c = a.clone();
            a.advance_to(1.0);
            auto b = build(s, k, &o);
            b.restore(cp);
            CHECK(b.time() == 0.5, "%s: restored time %g", name, b.time());
            b.advance_to(1.0);
            c.advance_to(1.0);
            CHECK(a.totals().events > 0 && a.time() == 1.0, "%s: %llu events", name,
                  static_cast<unsigned long long>(a.totals().events));
            CHECK(state_of(s, b) == state_of(s, a), "%s: restored run differs", name);
            CHECK(state_of(s, c) == state_of(s, a), "%s: clone differs", name);
            CHECK(b.checkpoint() == a.checkpoint(), "%s: the restored sim's checkpoint differs", name);
            CHECK(c.checkpoint() == a.checkpoint(), "%s: the clone's checkpoint differs", name);
            // the same seed gives the same bits, another stream another run (save for
            // deterministic quasi-Monte Carlo points, the mass-flow default)
            auto same = build(s, k, &o);
            same.advance_to(0.5);
            same.advance_to(1.0);
            CHECK(same.checkpoint() == a.checkpoint(), "%s: same seed, other bits", name);
            Options o2 = o.clone();
            o2.set("stream", 4);
            auto other_stream = build(s, k, &o2);
            other_stream.advance_to(1.0);
            bool qmc = std::find(s.options.begin(), s.options.end(), "points") != s.options.end();
            CHECK(qmc || state_of(s, other_stream) != state_of(s, a), "%s: another stream, the same run", name);
            CHECK(a.particle_count() > 0 && std::isfinite(a.moment(1.0)) && a.moment(0.0) > 0, "%s: moments", name);
            for (const auto &obs : s.observables)
                CHECK(std::isfinite(a.observable(obs)), "%s: observable %s", name, obs.c_str());
            CHECK(code_of([&] { a.observable("no-such-observable"); }) == COAG_UNSUPPORTED, "%s: observable", name);
            bool engines = std::find(s.options.begin(), s.options.end(), "engine") != s.options.end();
            if (engines)
                CHECK(a.engine() == "slots" || a.engine() == "counted", "%s: engine %s", name, a.engine().c_str());
            else
                CHECK(code_of([&] { a.engine(); }) == COAG_UNSUPPORTED, "%s has no engine", name);
            // a checkpoint of another scheme is refused, the sim unchanged
            if (s.index > 0) {
                auto other = coagula::scheme_info(0);
                Options o0;
                auto x = build(other, kernel_for(other), &o0);
                auto kept = a.checkpoint();
                CHECK(code_of([&] { a.restore(x.checkpoint()); }) == COAG_BAD_CHECKPOINT, "%s: foreign checkpoint", name);
                CHECK(a.checkpoint() == kept, "%s: a refused restore changed the sim", name);
            }
            // caller-owned memory: the same run in a workspace
            if (s.memory == COAG_MEMORY_FIXED && s.takes(COAG_INIT_SIZES)) {
                std::size_t bytes = Sim::workspace_size(s.name, 1024, &o);
                std::vector<double> ws(bytes / sizeof(double) + 1);
                auto w = Sim::from_sizes_in(s.name, k, std::vector<double>(1024, 1.0), 1.0, ws.data(), bytes, &o);
                w.advance_to(0.5);
                w.advance_to(1.0);
                CHECK(w.sizes() == a.sizes() && w.clone().sizes() == a.sizes(), "%s: workspace run differs", name);
            } else {
                CHECK(code_of([&] { Sim::workspace_size(s.name, 1024, &o); }) == COAG_UNSUPPORTED, "%s: no workspace",
                      name);
            }
            if (s.takes(COAG_INIT_COUNTS)) {
                double v = 0;
                auto dense = a.counts(&v);
                auto p = a.pairs();
                CHECK(v == 2000.0 && p.volume == 2000.0 && p.sizes.size() == a.occupied(), "%s: pairs", name);
                CHECK(dense.size() == a.state_len() && dense[p.sizes.back() - 1] == p.counts.back(), "%s: dense", name);
                auto d = a.clone();
                d.set_counts({}, 1.0);
                CHECK(d.particle_count() == 0 && d.state_len() == 0 && d.counts().empty() && d.pairs().sizes.empty(),
                      "%s: an empty system", name);
                d.set_pairs(p);
                CHECK(d.counts() == dense, "%s: set_pairs", name);
                d.set_counts(dense, 2000.0);
                d.set_kernel(Kernel::constant(2.0));
                d.advance_to(1.5);
                CHECK(d.time() == 1.5 && d.concentration(1.0, 1.0) >= 0 && d.gel_mass() > 0, "%s: observables", name);
                {
                    const std::vector<double> c = d.class_concentrations({1.0, 2.0, 1e300});
                    CHECK(c.size() == 2 && c[0] == d.concentration(1.0, 1.0) &&
                              std::fabs(c[0] + c[1] - d.moment(0.0)) <= 1e-12 * d.moment(0.0),
                          "%s: half-open classes", name);
                }
                CHECK(code_of([&] { a.sizes(); }) == COAG_UNSUPPORTED, "%s: no sizes", name);
            }
        }, &msg);
        CHECK(code == COAG_OK, "scheme %s: %s", name, msg.c_str());
    }
}

/// Marcus–Lushnikov with K = 1 from N0 monomers in volume N0: M0(t) = 1/(1 + t/2).
void test_constant_kernel_lowrank() {
    auto k = Kernel::constant(1.0);
    const std::uint64_t n0 = 1u << 13;
    std::vector<double> m0;
    for (int r = 0; r < kReplicas; ++r) {
        Options o;
        o.set("seed", 31).set("stream", r);
        auto sim = Sim::from_counts("lowrank", k, {n0}, static_cast<double>(n0), &o);
        for (int h = 1; h <= 10; ++h) sim.advance_to(0.2 * h);
        m0.push_back(sim.moment(0.0));
    }
    auto st = stat(m0);
    double exact = coagula::exact_moment(COAG_EXACT_CONSTANT, 0, 2.0);
    CHECK(exact == 1.0 / (1.0 + 2.0 / 2.0), "exact M0(2) %g", exact);
    CHECK(std::fabs(st.mean - exact) < kTolerance * st.se, "lowrank M0(2) %g +- %g vs %g", st.mean, st.se, exact);
    // the engine option pins the bucketed scheme's engine
    for (const char *e : {"slots", "counted"}) {
        Options o;
        o.set("engine", e);
        CHECK(Sim::from_counts("lowrank", k, {n0}, 1.0 * n0, &o).engine() == e, "engine %s", e);
    }
}

/// The time-driven mass-flow scheme with Monte Carlo points, K = 1: M2(t) = 1 + t.
void test_constant_kernel_massflow() {
    auto k = Kernel::constant(1.0);
    std::vector<double> m2;
    for (int r = 0; r < kReplicas; ++r) {
        Options o;
        o.set("points", "mc").set("seed", 5).set("stream", r);
        auto sim = Sim::from_sizes("massflow", k, std::vector<double>(4096, 1.0), 1.0, &o);
        sim.advance_to(1.0);
        m2.push_back(sim.moment(2.0));
    }
    auto st = stat(m2);
    CHECK(std::fabs(st.mean - 2.0) < kTolerance * st.se && st.se > 0, "massflow M2(1) %g +- %g vs 2", st.mean, st.se);
    CHECK(coagula::exact_moment(COAG_EXACT_CONSTANT, 2, 1.0) == 2.0, "exact M2(1)");
}

/// What a host changes between steps, the callbacks, and errors as codes.
void test_verbs_and_errors() {
    auto k = Kernel::constant(1.0);
    std::string msg;
    // an unknown scheme
    CHECK(code_of([&] { Sim::from_counts("no-such-scheme", k, {100}, 100.0); }, &msg) == COAG_INVALID_ARGUMENT &&
              contains(msg, "lowrank") && msg.rfind("COAG_INVALID_ARGUMENT: ", 0) == 0,
          "unknown scheme: %s", msg.c_str());
    CHECK(code_of([&] { coagula::scheme_find("nope"); }) == COAG_INVALID_ARGUMENT, "scheme_find");
    // an option that does not apply to the scheme
    {
        Options o;
        o.set("dt", 0.05);
        CHECK(code_of([&] { Sim::from_counts("lowrank", k, {100}, 100.0, &o); }, &msg) == COAG_UNSUPPORTED &&
                  contains(msg, "dt"),
              "dt on lowrank: %s", msg.c_str());
        auto copy = o.clone();
        CHECK(code_of([&] { Sim::from_counts("inverse", k, {100}, 100.0, &copy); }) == COAG_UNSUPPORTED, "clone");
        CHECK(Sim::from_sizes("massflow", k, std::vector<double>(64, 1.0), 1.0, &copy).scheme() == "massflow", "dt");
    }
    // bad options, bad kernel parameters
    Options o;
    CHECK(code_of([&] { o.set("no-such-key", 1.0); }) == COAG_INVALID_ARGUMENT, "unknown key");
    CHECK(code_of([&] { o.set("points", "qmc"); }, &msg) == COAG_INVALID_ARGUMENT && contains(msg, "points"),
          "bad name: %s", msg.c_str());
    CHECK(code_of([&] { o.set("seed", -1); }) == COAG_INVALID_ARGUMENT, "negative count");
    CHECK(code_of([&] { o.set("dt", -1.0); }) == COAG_INVALID_ARGUMENT, "negative dt");
    CHECK(code_of([&] { o.set("batched-clock", false).set("size-limit", 1e6).set("memory-budget", 1u << 30); }) ==
              COAG_OK,
          "flag, count as real, count");
    CHECK(code_of([&] { Kernel::constant(-1.0); }, &msg) == COAG_INVALID_ARGUMENT && contains(msg, "coefficient"),
          "bad coefficient: %s", msg.c_str());
    CHECK(code_of([&] { Kernel::builtin("product"); }) == COAG_INVALID_ARGUMENT, "required parameter missing");
    CHECK(code_of([&] { Kernel::builtin("no-such-kernel"); }) == COAG_INVALID_ARGUMENT, "unknown kernel");
    // initial states and physics a scheme does not take
    CHECK(code_of([&] { Sim::from_sizes("lowrank", k, {1.0, 2.0}, 1.0); }) == COAG_UNSUPPORTED, "sizes on lowrank");
    auto tk = Kernel::builtin("temperature-closed-form");
    CHECK(code_of([&] { Sim::from_counts("lowrank", tk, {100}, 100.0); }) == COAG_UNSUPPORTED, "temperature model");
    CHECK(code_of([&] { Sim::from_temperatures("temperature", tk, {10}, {1.0, 2.0}, 10.0); }) != COAG_OK, "lengths");

    // a size-count sim: work limit, cancellation, host random stream, reentrancy
    Options so;
    so.set("seed", 5);
    auto a = Sim::from_counts("inverse", k, {2000, 10}, 2000.0, &so);
    a.reseed(5, 1);
    a.set_work_limit(300);
    CHECK(code_of([&] { a.advance_to(1.0); }) == COAG_INTERRUPTED, "interrupted throws from advance_to");
    coag_step_report rep = coagula::step_report();
    int stops = 0;
    while (!a.advance_within(1.0, &rep)) ++stops;
    CHECK(stops > 0 && a.time() == 1.0 && rep.time == 1.0, "work limit: %d stops", stops);
    a.set_work_limit(0);
    CHECK(code_of([&] { a.advance_to(0.5); }) == COAG_TIME_BACKWARDS, "time backwards");
    struct Xorshift {
        std::uint64_t x = 88172645463325252ull;
    } xs;
    a.set_rng_callback(
        [](void *p) -> std::uint64_t {
            auto *g = static_cast<Xorshift *>(p);
            g->x ^= g->x << 13;
            g->x ^= g->x >> 7;
            g->x ^= g->x << 17;
            return g->x;
        },
        &xs);
    a.advance_to(1.5);
    auto before = a.checkpoint();
    a.set_rng_callback([](void *) -> std::uint64_t { return 42; }, nullptr);
    CHECK(code_of([&] { a.advance_to(2.0); }) == COAG_RNG_FAILURE && a.checkpoint() == before, "stuck rng undone");
    a.set_rng_callback(nullptr, nullptr);
    a.advance_to(2.0);
    CHECK(a.time() == 2.0, "own stream again");
    // the time-driven mass-flow scheme: setters, cancellation, a callback re-entering
    auto f = coagula::Fragmentation::binary_uniform(1.0);
    Options mo;
    mo.set("seed", 3);
    auto m = Sim::from_sizes("massflow", k, std::vector<double>(1024, 1.0), 1.0, &mo, &f);
    m.set_dt(0.05);
    m.set_mass(2.0);
    CHECK(std::fabs(m.moment(1.0) - 2.0) < 1e-12, "set_mass: M1 %g", m.moment(1.0));
    rep = m.advance_to(0.5);
    CHECK(rep.proposals == 10u * 1024 && rep.time == 0.5, "dt 0.05: %llu proposals in 10 steps",
          static_cast<unsigned long long>(rep.proposals));
    CHECK(std::fabs(m.moment(1.0) - 2.0) < 1e-9, "mass conserved: M1 %g", m.moment(1.0));
    m.set_time(3.0);
    CHECK(m.time() == 3.0 && m.totals().events > 0 && m.occupied() == 1024 && m.state_len() == 1024,
          "set_time, totals, occupied");
    m.set_fragmentation(nullptr);
    m.set_sizes(std::vector<double>(1024, 2.0));
    CHECK(m.sizes() == std::vector<double>(1024, 2.0), "set_sizes");
    // refusals leave the sim as it was
    auto kept = m.checkpoint();
    CHECK(code_of([&] { m.set_dt(-1.0); }) == COAG_INVALID_ARGUMENT, "negative dt");
    CHECK(code_of([&] { m.set_mass(std::nan("")); }) == COAG_INVALID_ARGUMENT, "NaN mass");
    CHECK(code_of([&] { m.set_time(-1.0); }) == COAG_INVALID_ARGUMENT, "negative time");
    CHECK(code_of([&] { m.set_sizes(std::vector<double>(1024, -1.0)); }) == COAG_INVALID_ARGUMENT, "negative sizes");
    CHECK(code_of([&] { m.set_sizes(std::vector<double>(1000, 1.0)); }) == COAG_BUFFER_TOO_SMALL,
          "another number of sizes");
    CHECK(code_of([&] { m.set_counts({10}, 10.0); }) == COAG_UNSUPPORTED, "counts on mass flow");
    CHECK(code_of([&] { m.advance_to(1.0); }) == COAG_TIME_BACKWARDS, "time backwards");
    CHECK(m.checkpoint() == kept, "refusals changed the mass-flow sim");
    // cancellation, polled before every step: the third poll stops the call
    int polls = 0;
    m.set_cancel_callback([](void *p) -> std::int32_t { return ++*static_cast<int *>(p) >= 3; }, &polls);
    CHECK(!m.advance_within(4.0, &rep) && polls == 3 && rep.time > 3.0 && rep.time < 4.0 && m.time() == rep.time,
          "cancelled after %d polls at %g", polls, rep.time);
    m.set_cancel_callback(nullptr, nullptr);
    CHECK(m.advance_within(4.0) && m.time() == 4.0, "continued to 4");
    // a callback calling back into its own sim is refused, nothing changed
    struct Reentry {
        coag_sim *sim;
        std::int32_t status;
    } re{m.get(), COAG_OK};
    m.set_cancel_callback(
        [](void *p) -> std::int32_t {
            auto *r = static_cast<Reentry *>(p);
            if (r->status == COAG_OK) r->status = coag_sim_set_dt(r->sim, 0.5);
            return 0;
        },
        &re);
    m.advance_to(4.5);
    CHECK(re.status == COAG_REENTRANT, "re-entering call: %s", coagula::status_name(re.status).c_str());
    m.set_cancel_callback(nullptr, nullptr);
    rep = m.advance_to(5.0);
    CHECK(rep.proposals == 10u * 1024, "dt kept at 0.05 after the refused call: %llu proposals",
          static_cast<unsigned long long>(rep.proposals));
}

/// User kernels and fragmentation from C callbacks.
double user_rate(double, double, void *ud) { return *static_cast<const double *>(ud); }
double user_sup(double, double, void *ud) { return std::fabs(*static_cast<const double *>(ud)); }
double user_block_sup(double, double, double, double, void *ud) { return std::fabs(*static_cast<const double *>(ud)); }
double user_majorant(double, void *ud) { return std::sqrt(std::fabs(*static_cast<const double *>(ud))); }
void user_factors(double, double *a, double *b, void *ud) {
    a[0] = 0.5 * std::fabs(*static_cast<const double *>(ud));
    b[0] = 1.0;
}
double frag_rate(double, void *) { return 1.0; }
// binary uniform break-up: the size-biased piece has F(y) = (y/x)^2
double frag_piece(double x, double u, void *) { return x * std::sqrt(u); }

/// K = 1 from callbacks against the exact M0(2) and n_1(2) (rejection, 32 replicas);
/// a negative rate at run time is COAG_INVALID_RATE with the sim as it was; Lécot's
/// coagulation-fragmentation test with the built-in and the user fragmentation.
void test_user_kernels() {
    double k0 = 1.0;
    coag_user_kernel desc{user_rate, user_majorant, 1, user_factors, 1, user_sup, &k0};
    auto uk = Kernel::user(desc);
    CHECK(uk.rate(2.0, 3.0) == 1.0, "user rate");
    std::vector<double> m0, n1;
    for (int r = 0; r < kReplicas; ++r) {
        Options o;
        o.set("seed", 40).set("stream", r);
        auto sim = Sim::from_counts("rejection", uk, {1u << 13}, 8192.0, &o);
        sim.advance_to(1.0);
        sim.advance_to(2.0);
        m0.push_back(sim.moment(0.0));
        n1.push_back(sim.concentration(1.0, 1.0));
    }
    auto s0 = stat(m0), s1 = stat(n1);
    double e0 = coagula::exact_moment(COAG_EXACT_CONSTANT, 0, 2.0), e1 = coagula::exact_density(COAG_EXACT_CONSTANT, 1, 2.0);
    CHECK(std::fabs(e1 - 0.25) < 1e-15, "exact n_1(2) %g", e1);
    CHECK(std::fabs(s0.mean - e0) < kTolerance * s0.se, "user kernel M0(2) %g +- %g vs %g", s0.mean, s0.se, e0);
    CHECK(std::fabs(s1.mean - e1) < kTolerance * s1.se, "user kernel n1(2) %g +- %g vs %g", s1.mean, s1.se, e1);
    {
        // a supremum over blocks, declared loose: lowrank runs block majorants
        auto ub = Kernel::user(desc);
        ub.set_user_blocks(user_block_sup, true);
        auto sim = Sim::from_counts("lowrank", ub, {2000}, 2000.0);
        sim.advance_to(1.0);
        CHECK(std::string(sim.engine()) == "blocks", "a loose user kernel on %s", sim.engine().c_str());
        CHECK(code_of([&] { Kernel::constant().set_user_blocks(user_block_sup, false); }) == COAG_UNSUPPORTED,
              "a block supremum on a built-in kernel");
    }
    coag_user_kernel norate = desc;
    norate.rate = nullptr;
    CHECK(code_of([&] { Kernel::user(norate); }) == COAG_INVALID_ARGUMENT, "a user kernel without a rate");
    coag_user_kernel rank9 = desc;
    rank9.rank = 9;
    CHECK(code_of([&] { Kernel::user(rank9); }) == COAG_INVALID_ARGUMENT, "rank above 8");
    {
        Options o;
        o.set("seed", 1);
        auto sim = Sim::from_counts("rejection", uk, {500, 20}, 520.0, &o);
        sim.advance_to(0.1);
        auto pairs = sim.pairs();
        double t = sim.time();
        k0 = -1.0;  // the callback now returns a negative rate
        CHECK(code_of([&] { sim.advance_to(1.0); }) == COAG_INVALID_RATE, "negative rate");
        auto after = sim.pairs();
        CHECK(after.sizes == pairs.sizes && after.counts == pairs.counts && sim.time() == t,
              "a refused event changed the sim (time %g vs %g)", sim.time(), t);
        k0 = 1.0;
        sim.advance_to(1.0);
        CHECK(sim.time() == 1.0 && sim.particle_count() < 520, "usable after the error");
    }
    // Lécot et al. §4: mass flow with binary uniform break-up, M2(1) within 0.02
    auto k = Kernel::constant(1.0);
    auto builtin = coagula::Fragmentation::binary_uniform(1.0);
    coag_user_fragmentation fd{frag_rate, frag_piece, 1.0, nullptr};
    auto user = coagula::Fragmentation::user(fd);
    double e2 = coagula::exact_moment(COAG_EXACT_COAG_FRAG, 2, 1.0);
    for (const coagula::Fragmentation *f : {&builtin, &user}) {
        Options o;
        o.set("seed", 8);
        auto sim = Sim::from_sizes("massflow", k, std::vector<double>(1024, 1.0), 1.0, &o, f);
        sim.advance_to(1.0);
        CHECK(std::fabs(sim.moment(2.0) - e2) < 0.02, "%s fragmentation: M2(1) %g vs %g",
              f == &builtin ? "built-in" : "user", sim.moment(2.0), e2);
    }
    coag_user_fragmentation nofrag{frag_rate, nullptr, 1.0, nullptr};
    CHECK(code_of([&] { coagula::Fragmentation::user(nofrag); }) == COAG_INVALID_ARGUMENT, "no inverse piece");
    CHECK(code_of([&] { coagula::Fragmentation::binary_uniform(-1.0); }) == COAG_INVALID_ARGUMENT, "negative lambda");
}

/// The mass flow algorithm with the multiplicative kernel: the gel mass at t = 2 is
/// 1 - 1/t = 0.5 (one run of 4096 particles with b_N = N: its SD is about 0.01);
/// direct simulation: a clone continues as the original.
void test_event_driven() {
    auto km = Kernel::multiplicative();
    Options o;
    o.set("truncation", 4096.0).set("seed", 3);
    auto e = Sim::from_sizes("mfa", km, std::vector<double>(4096, 1.0), 1.0, &o);
    e.advance_to(2.0);
    CHECK(std::fabs(e.gel_mass() - 0.5) < 0.06, "MFA gel mass %g", e.gel_mass());
    Options d;
    d.set("seed", 4);
    auto a = Sim::from_sizes("dsa", km, std::vector<double>(512, 1.0), 1.0, &d);
    a.advance_to(0.5);
    auto c = a.clone();
    a.advance_to(1.5);
    c.advance_to(1.5);
    CHECK(a.sizes() == c.sizes() && a.totals().events > 0, "DSA clone differs");
}

/// The closed-form temperature model (TEMPERATURE.md, core's ClosedFormSolution):
/// from n_1(0) = n0, T_1(0) = T0, u(t) = [1 + (1+g) c n0 sqrt(T0) t / 2]^(1/(1+g)),
/// N(t) = n0 / u, mean temperature T0 u^(1-2g). Both temperature schemes, 32 replicas.
void test_temperature() {
    const double c = 1.0, g = 1.0, t = 4.0;
    double u = std::pow(1.0 + (1.0 + g) * c * t / 2.0, 1.0 / (1.0 + g));
    auto tk = Kernel::builtin("temperature-closed-form", {c, g});
    for (const char *scheme : {"temperature", "temperature-rejection"}) {
        std::vector<double> n, temp;
        for (int r = 0; r < kReplicas; ++r) {
            Options o;
            o.set("seed", 42).set("stream", r);
            auto sim = Sim::from_temperatures(scheme, tk, {20000}, {1.0}, 20000.0, &o);
            sim.advance_to(t);
            n.push_back(sim.moment(0.0));
            temp.push_back(sim.observable("mean-temperature"));
        }
        auto sn = stat(n), st = stat(temp);
        CHECK(std::fabs(sn.mean - 1.0 / u) < kTolerance * sn.se, "%s N(4) %g +- %g vs %g", scheme, sn.mean, sn.se,
              1.0 / u);
        CHECK(std::fabs(st.mean - std::pow(u, 1.0 - 2.0 * g)) < kTolerance * st.se, "%s T(4) %g +- %g vs %g", scheme,
              st.mean, st.se, std::pow(u, 1.0 - 2.0 * g));
    }
    auto sim = Sim::from_temperatures("temperature", tk, {3000, 200}, {1.0, 1.5}, 30000.0);
    auto tv = sim.size_values("temperature");
    CHECK(tv.sizes == std::vector<std::uint64_t>({1, 2}) && tv.values == std::vector<double>({1.0, 1.5}),
          "partial temperatures read back");
    CHECK(code_of([&] { sim.size_values("no-such-quantity"); }) == COAG_UNSUPPORTED, "unknown per-size quantity");
    sim.advance_to(5.0);
    CHECK(sim.observable("energy") > 0 && sim.moment(1.0) > 0, "temperature observables");
}

/// A gas of hard spheres with restitution 1: elastic collisions conserve momentum and
/// energy; particles given are read back as given.
// sources, removal and growth: the books balance; errors as exceptions
void test_processes() {
    auto k = Kernel::constant(1.0);
    Options o;
    o.set("seed", 9);
    auto sim = Sim::from_counts("lowrank", k, {800, 50}, 900.0, &o);
    sim.set_source(0.4, COAG_SOURCE_LOGNORMAL, 2.0, 1.5);
    sim.set_removal(0.1, 0.0);
    sim.set_growth(0.05, 1.0);
    sim.advance_to(2.0);
    coag_books b = sim.books();
    double mass = b.initial_mass + b.injected_mass - b.removed_mass + b.grown_mass;
    double n = static_cast<double>(b.initial_number + b.injected_number - b.removed_number - b.merged);
    CHECK(n == static_cast<double>(sim.particle_count()), "books: the number");
    CHECK(std::fabs(mass - sim.moment(1.0) * n / sim.moment(0.0)) < 1e-9 * mass, "books: the mass");
    CHECK(code_of([&] { sim.set_removal(1.0, 3.0); }) == COAG_INVALID_ARGUMENT, "removal exponent 3");
    sim.clear_processes();
    CHECK(code_of([&] { sim.books(); }) == COAG_UNSUPPORTED, "no books without processes");
    sim.set_source_sizes(0.3, {1.0, 4.0});
    sim.set_source_schedule({3.0, 5.0}, {0.0, 0.2});
    // a host's removal rate: within its bound it runs, above it the advance refuses
    static double lam = 0.2;
    auto rate = [](double, void *ud) -> double { return *static_cast<double *>(ud); };
    sim.set_removal_callback(rate, &lam, 0.5, 3);
    sim.advance_to(sim.time() + 0.5);
    sim.set_removal_callback(rate, &lam, 0.1, 3);
    CHECK(code_of([&] { sim.advance_to(sim.time() + 5.0); }) == COAG_INVALID_RATE, "a host rate above its bound");
    sim.set_removal_callback(nullptr, nullptr, 1.0);
    CHECK(code_of([&] { sim.set_source_schedule({3.0}, {0.0, 0.2}); }) == COAG_INVALID_ARGUMENT, "schedule lengths");
    CHECK(code_of([&] { sim.set_source_sizes(0.3, {1.0}); }) == COAG_BUFFER_TOO_SMALL, "a listed source of one size");
    sim.clear_processes();
    // host classes: number and mass kept; built back within one particle per class
    std::vector<double> x{1, 2, 4, 8, 16, 64, 1024}, cn, back;
    auto out = sim.project(x, cn);
    double nn = out[0] + out[2], mm = out[1] + out[3];
    for (std::size_t i = 0; i < x.size(); i++) {
        nn += cn[i];
        mm += cn[i] * x[i];
    }
    CHECK(std::fabs(nn - sim.moment(0.0)) < 1e-12 * nn, "classes: the number");
    CHECK(std::fabs(mm - sim.moment(1.0)) < 1e-12 * mm, "classes: the mass");
    double v = static_cast<double>(sim.particle_count()) / sim.moment(0.0);
    sim.set_classes(x, cn);
    sim.project(x, back);
    bool within = true;
    for (std::size_t i = 0; i < x.size(); i++) within &= std::fabs(back[i] - cn[i]) * v <= 1.0 + 1e-9;
    CHECK(within, "classes: within one particle");
    auto r = coagula::class_rates(cn, back, 0.5);
    CHECK(r[0] == (back[0] - cn[0]) / 0.5, "classes: rates");
    CHECK(code_of([&] { sim.set_classes(x, {1.0}); }) == COAG_INVALID_ARGUMENT, "classes: lengths");
    // core's sectional reference: M0 = 2 / (2 + t) for the constant kernel from monomers
    std::vector<double> piv;
    for (int i = 1; i <= 64; i++) piv.push_back(i);
    coagula::Sectional sec(k, piv);
    sec.add(1.0, 1.0);
    sec.advance_to(1.0, 1e-3);
    CHECK(std::fabs(sec.moment(0.0) - 2.0 / 3.0) < 1e-10 && sec.time() == 1.0, "sectional: M0");
    sec.set_processes(0.5, 1.0, 0.25, 0.0, 0.0, 0.0);
    sec.advance_to(3.0, 1e-3);
    CHECK(std::fabs(sec.moment(1.0) - (2.0 - std::exp(-0.5))) < 1e-8, "sectional: M1 with a source and dilution");
    auto nums = sec.numbers();
    CHECK(nums.size() == piv.size(), "sectional: numbers");
    CHECK(code_of([&] { sec.set_numbers({1.0}); }) == COAG_BUFFER_TOO_SMALL, "sectional: numbers' length");
    CHECK(code_of([&] { sec.advance_to(1.0, 1e-3); }) == COAG_TIME_BACKWARDS, "sectional: backwards");
}

void test_gas() {
    auto hs = Kernel::builtin("hard-spheres", {1.0});
    Options o;
    o.set("seed", 6);
    auto a = Sim::from_maxwellian("dsmc", hs, {300, 100}, {1.0, 2.0}, 4000.0, &o);
    const char *p[3] = {"momentum-x", "momentum-y", "momentum-z"};
    double p0[3], e0 = a.observable("energy");
    for (int i = 0; i < 3; ++i) p0[i] = a.observable(p[i]);
    auto rep = a.advance_to(10.0);
    CHECK(rep.events > 100 && a.particle_count() == 400, "dsmc: %llu collisions",
          static_cast<unsigned long long>(rep.events));
    for (int i = 0; i < 3; ++i)
        CHECK(std::fabs(a.observable(p[i]) - p0[i]) < 1e-9, "%s %g vs %g", p[i], a.observable(p[i]), p0[i]);
    CHECK(std::fabs(a.observable("energy") - e0) < 1e-12 * e0, "energy %.17g vs %.17g", a.observable("energy"), e0);
    CHECK(a.observable("mean-temperature") > 0, "mean temperature");
    std::vector<std::uint64_t> sizes{1, 2};
    std::vector<double> vel{1.0, 0.0, 0.0, -1.0, 0.5, 0.0};
    auto b = Sim::from_velocities("dsmc-rejection", hs, sizes, vel, 10.0);
    auto bp = b.particles();
    CHECK(b.particle_count() == 2 && bp.sizes == sizes && bp.velocities == vel, "particles read back");
    CHECK(code_of([&] { Sim::from_velocities("dsmc", hs, {1}, {std::nan(""), 0.0, 0.0}, 10.0); }) == COAG_INVALID_ARGUMENT,
          "a NaN velocity");
    CHECK(code_of([&] { Sim::from_counts("lowrank", Kernel::constant(), {10}, 10.0).particles(); }) ==
              COAG_UNSUPPORTED,
          "no velocities on lowrank");
}

/// Langevin batches: b = 0 outside the unit ball keeps E|U|^2 = |u0|^2 + 3 T (4.89 SE),
/// caller memory, a clone and a checkpoint continue bit for bit, bounded calls, errors.
void test_langevin() {
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
    CHECK(e.count == 0, "specular wall: none absorbed");
    auto x = b.positions();
    bool outside = true;
    for (std::size_t i = 0; i < 20000; ++i)
        outside = outside && x[3 * i] * x[3 * i] + x[3 * i + 1] * x[3 * i + 1] + x[3 * i + 2] * x[3 * i + 2] >= 1.0 - 1e-12;
    CHECK(outside, "positions outside the ball");
    auto hits = b.hits();
    auto first = b.first_hits();
    std::uint64_t total = 0;
    for (auto h : hits) total += h;
    CHECK(b.mean().mean > 0.5 && hits.size() == 20000 && first.size() == 20000 &&
              std::fabs(b.mean().mean - total / 20000.0) < 1e-12 && *std::min_element(first.begin(), first.end()) > 0,
          "hits");
    auto p = coagula::langevin_default_config();
    p.drift = COAG_DRIFT_MAFTEI2016;
    p.dt = 0.1;
    p.period = 1.0;
    std::size_t bytes = coagula::langevin_workspace_size(p, 500);
    std::vector<double> ws(bytes / sizeof(double) + 1);
    auto own = coagula::Langevin::make(p, 500, {0.5}, {-1.5}, 9);
    auto mine = coagula::Langevin::make_in(p, 500, {0.5}, {-1.5}, 9, 0, ws.data(), bytes);
    own.advance_to(1.6);
    mine.advance_to(1.6);
    auto cp = mine.checkpoint();
    auto twin = own.clone();
    own.advance_to(3.2);
    mine.advance_to(3.2);
    twin.advance_to(3.2);
    mine.restore(cp);
    CHECK(mine.time() == 1.6, "restored time %g", mine.time());
    mine.advance_to(3.2);
    CHECK(own.positions() == mine.positions() && own.velocities() == mine.velocities() && own.hits() == mine.hits(),
          "caller memory and restore continue bit for bit");
    CHECK(twin.positions() == own.positions() && twin.velocities() == own.velocities(), "clone continues bit for bit");
    // errors leave the batch as it was
    auto before = own.checkpoint();
    CHECK(code_of([&] { own.advance_to(1.0); }) == COAG_TIME_BACKWARDS, "time backwards");
    CHECK(code_of([&] { own.restore({1, 2, 3}); }) == COAG_BAD_CHECKPOINT, "garbage checkpoint");
    auto c3 = coagula::langevin_default_config();
    c3.dim = 3;
    c3.radius = 1.0;
    CHECK(code_of([&] { own.restore(coagula::Langevin::make(c3, 10, {2, 0, 0}, {0, 0, 0}, 1).checkpoint()); }) ==
              COAG_BAD_CHECKPOINT,
          "another batch's checkpoint");
    CHECK(own.checkpoint() == before, "refusals changed the batch");
    CHECK(code_of([&] { coagula::Langevin::make(p, 0, {0.5}, {0.0}, 1); }) == COAG_INVALID_ARGUMENT, "no trajectory");
    CHECK(code_of([&] { coagula::Langevin::make(p, 10, {-0.5}, {0.0}, 1); }) == COAG_INVALID_ARGUMENT, "behind wall");
    // bounded calls: a work limit and a cancellation callback stop and resume the run
    auto w = own.clone(), ref = own.clone();
    w.set_work_limit(500 * 3);
    coag_step_report rep = coagula::step_report();
    int stops = 0;
    while (!w.advance_within(5.0, &rep)) ++stops;
    ref.advance_to(5.0);
    CHECK(stops >= 4 && w.time() == 5.0 && w.positions() == ref.positions(), "work limit: %d stops", stops);
    w.set_work_limit(0);
    int polls = 0;
    w.set_cancel_callback([](void *q) -> std::int32_t { return ++*static_cast<int *>(q) >= 1; }, &polls);
    CHECK(!w.advance_within(1000.0) && polls >= 1 && w.time() > 5.0 && w.time() < 1000.0, "cancelled at %g", w.time());
    w.set_cancel_callback(nullptr, nullptr);
    // the free-flight kernel in 2-D from first hits: 2 R <|v|> = 2 R sqrt(pi/2) sd
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
    CHECK(std::fabs(k2.mean - exact) < 4.89 * k2.std_error && k2.count > 100, "2-D free-flight kernel %g +- %g",
          k2.mean, k2.std_error);
    fh.outer = 0.4;
    CHECK(code_of([&] { coagula::first_hit_kernel(fh, 3); }) == COAG_INVALID_ARGUMENT, "outer < radius");
}

}  // namespace

int main() {
    std::string msg;
    int code = code_of([] {
        test_tables();
        test_every_scheme();
        test_constant_kernel_lowrank();
        test_constant_kernel_massflow();
        test_verbs_and_errors();
        test_user_kernels();
        test_event_driven();
        test_temperature();
        test_gas();
        test_processes();
        test_langevin();
    }, &msg);
    CHECK(code == COAG_OK, "uncaught: %s", msg.c_str());
    std::printf("test_cpp: %d passed, %d failed\n", checks - failures, failures);
    return failures ? 1 : 0;
}
