// coagula.hpp — header-only C++17 wrapper over the C ABI of libcoagula.
//
// RAII handles (move-only), exceptions from status codes (coagula::Error carries the
// code and the library's message), std::vector in and out. Same threading rules as
// the C API: one thread at a time per object.
#ifndef COAGULA_HPP
#define COAGULA_HPP

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "coagula.h"

namespace coagula {

/// A failed call: the COAG_* status and the library's message.
class Error : public std::runtime_error {
  public:
    Error(int code, const std::string &msg) : std::runtime_error(msg), code_(code) {}
    int code() const noexcept { return code_; }

  private:
    int code_;
};

/// Throws coagula::Error unless `status` is COAG_OK.
inline void check(std::int32_t status) {
    if (status == COAG_OK) return;
    size_t len = 0;
    coag_last_error_message(nullptr, 0, &len);
    std::string msg(len + 1, '\0');
    coag_last_error_message(&msg[0], msg.size(), nullptr);
    msg.resize(len);
    throw Error(status, std::string(coag_status_name(status)) + ": " + msg);
}

namespace detail {
struct KernelFree {
    void operator()(coag_kernel *k) const noexcept { coag_kernel_free(k); }
};
struct FragFree {
    void operator()(coag_fragmentation *f) const noexcept { coag_fragmentation_free(f); }
};
struct SimFree {
    void operator()(coag_sim *s) const noexcept { coag_sim_free(s); }
};
struct LangevinFree {
    void operator()(coag_langevin *h) const noexcept { coag_langevin_free(h); }
};
struct ThermalFree {
    void operator()(coag_thermal *h) const noexcept { coag_thermal_free(h); }
};
struct DsmcFree {
    void operator()(coag_dsmc *h) const noexcept { coag_dsmc_free(h); }
};
}  // namespace detail

/// A coagulation kernel.
class Kernel {
  public:
    static Kernel constant(double k0) { return make([&](coag_kernel **o) { return coag_kernel_new_constant(k0, o); }); }
    static Kernel additive(double min_size = 0.0) {
        return make([&](coag_kernel **o) { return coag_kernel_new_additive(min_size, o); });
    }
    static Kernel multiplicative() { return make([](coag_kernel **o) { return coag_kernel_new_multiplicative(o); }); }
    static Kernel product(double a) { return make([&](coag_kernel **o) { return coag_kernel_new_product(a, o); }); }
    static Kernel homogeneous(double gamma) {
        return make([&](coag_kernel **o) { return coag_kernel_new_homogeneous(gamma, o); });
    }
    static Kernel free_molecular(double min_size = 0.0) {
        return make([&](coag_kernel **o) { return coag_kernel_new_free_molecular(min_size, o); });
    }
    static Kernel brownian() { return make([](coag_kernel **o) { return coag_kernel_new_brownian(o); }); }
    /// A kernel from C callbacks (see coag_user_kernel); user_data must outlive every
    /// object made from it.
    static Kernel user(const coag_user_kernel &desc) {
        return make([&](coag_kernel **o) { return coag_kernel_new_user(&desc, o); });
    }

    double rate(double x, double y) const {
        double v;
        check(coag_kernel_rate(k_.get(), x, y, &v));
        return v;
    }
    const coag_kernel *get() const noexcept { return k_.get(); }

  private:
    template <class F>
    static Kernel make(F f) {
        coag_kernel *k = nullptr;
        check(f(&k));
        Kernel out;
        out.k_.reset(k);
        return out;
    }
    std::unique_ptr<coag_kernel, detail::KernelFree> k_;
};

/// A fragmentation kernel.
class Fragmentation {
  public:
    static Fragmentation binary_uniform(double lambda) {
        coag_fragmentation *f = nullptr;
        check(coag_fragmentation_new_binary_uniform(lambda, &f));
        Fragmentation out;
        out.f_.reset(f);
        return out;
    }
    static Fragmentation user(const coag_user_fragmentation &desc) {
        coag_fragmentation *f = nullptr;
        check(coag_fragmentation_new_user(&desc, &f));
        Fragmentation out;
        out.f_.reset(f);
        return out;
    }
    const coag_fragmentation *get() const noexcept { return f_.get(); }

  private:
    std::unique_ptr<coag_fragmentation, detail::FragFree> f_;
};

/// The library version.
inline std::string version() { return coag_version(); }
/// The name of a status code.
inline std::string status_name(std::int32_t status) { return coag_status_name(status); }
/// The message of the last failed call on this thread.
inline std::string last_error_message() {
    size_t len = 0;
    coag_last_error_message(nullptr, 0, &len);
    std::string msg(len + 1, '\0');
    coag_last_error_message(&msg[0], msg.size(), nullptr);
    msg.resize(len);
    return msg;
}
/// Exact moment M_m(t) of a COAG_EXACT_* solution.
inline double exact_moment(std::int32_t solution, std::uint32_t m, double t) {
    double v;
    check(coag_exact_moment(solution, m, t, &v));
    return v;
}
/// Exact concentration n_k(t) of a COAG_EXACT_* solution.
inline double exact_density(std::int32_t solution, std::uint64_t k, double t) {
    double v;
    check(coag_exact_density(solution, k, t, &v));
    return v;
}
/// Bytes of workspace a mass-flow sim of n particles needs (Sim::massflow_in).
inline std::size_t massflow_workspace_size(std::size_t n) {
    size_t b;
    check(coag_massflow_workspace_size(n, &b));
    return b;
}
/// A zeroed step report with its struct_size set.
inline coag_step_report step_report() {
    coag_step_report r;
    check(coag_step_report_init(&r, sizeof r));
    return r;
}

inline coag_massflow_config massflow_default_config() {
    coag_massflow_config c;
    check(coag_massflow_default_config(&c, sizeof c));
    return c;
}

inline coag_counts_config counts_default_config() {
    coag_counts_config c;
    check(coag_counts_default_config(&c, sizeof c));
    return c;
}

/// Bytes of workspace an event-driven sim of n particles needs (Sim::eventflow_in).
inline std::size_t eventflow_workspace_size(const coag_eventflow_config &c, const Fragmentation *f, std::size_t n) {
    size_t b;
    check(coag_eventflow_workspace_size(&c, f ? f->get() : nullptr, n, &b));
    return b;
}

inline coag_eventflow_config eventflow_default_config() {
    coag_eventflow_config c;
    check(coag_eventflow_default_config(&c, sizeof c));
    return c;
}

/// A simulation: any scheme, stepped with advance_to.
class Sim {
  public:
    /// The time-driven mass-flow scheme over `sizes` (a power of two of them).
    static Sim massflow(const coag_massflow_config &c, const Kernel &k, const Fragmentation *f,
                        const std::vector<double> &sizes) {
        coag_sim *s = nullptr;
        check(coag_massflow_new(&c, k.get(), f ? f->get() : nullptr, sizes.data(), sizes.size(), &s));
        return Sim(s);
    }
    /// The mass-flow scheme in caller-owned memory (`bytes` ≥ massflow_workspace_size,
    /// aligned for double), which must outlive the Sim.
    static Sim massflow_in(const coag_massflow_config &c, const Kernel &k, const Fragmentation *f,
                           const std::vector<double> &sizes, void *workspace, std::size_t bytes) {
        coag_sim *s = nullptr;
        check(coag_massflow_new_in(&c, k.get(), f ? f->get() : nullptr, sizes.data(), sizes.size(), workspace,
                                   bytes, &s));
        return Sim(s);
    }
    /// An event-driven scheme over the particle sizes `sizes` (c.method: Eibeck &
    /// Wagner's COAG_EVENTFLOW_MFA or COAG_EVENTFLOW_DSA, or Osinsky's low-rank
    /// COAG_EVENTFLOW_LOWRANK); `f` may be null.
    static Sim eventflow(const coag_eventflow_config &c, const Kernel &k, const Fragmentation *f,
                         const std::vector<double> &sizes) {
        coag_sim *s = nullptr;
        check(coag_eventflow_new(&c, k.get(), f ? f->get() : nullptr, sizes.data(), sizes.size(), &s));
        return Sim(s);
    }
    /// The event-driven scheme in caller-owned memory (`bytes` ≥ eventflow_workspace_size,
    /// aligned for double), which must outlive the Sim.
    static Sim eventflow_in(const coag_eventflow_config &c, const Kernel &k, const Fragmentation *f,
                            const std::vector<double> &sizes, void *workspace, std::size_t bytes) {
        coag_sim *s = nullptr;
        check(coag_eventflow_new_in(&c, k.get(), f ? f->get() : nullptr, sizes.data(), sizes.size(), workspace,
                                    bytes, &s));
        return Sim(s);
    }
    /// A size-count scheme: counts[i] particles of size i + 1.
    static Sim counts(const coag_counts_config &c, const Kernel &k, const std::vector<std::uint64_t> &counts) {
        coag_sim *s = nullptr;
        check(coag_counts_new(&c, k.get(), counts.data(), counts.size(), &s));
        return Sim(s);
    }
    /// An exact, independent copy (coag_sim_clone).
    Sim clone() const {
        coag_sim *s = nullptr;
        check(coag_sim_clone(s_.get(), &s));
        return Sim(s);
    }

    /// Runs to t; a call stopped by its work limit or cancellation throws coagula::Error
    /// with code COAG_INTERRUPTED (see advance_within to continue instead).
    coag_step_report advance_to(double t) {
        coag_step_report r = step_report();
        check(coag_sim_advance_to(s_.get(), t, &r));
        return r;
    }
    /// Runs towards t; returns false when the work limit or the cancellation callback
    /// stopped the call (the sim is consistent at report->time; call again), true when t
    /// was reached. Errors throw.
    bool advance_within(double t, coag_step_report *report = nullptr) {
        coag_step_report r = step_report();
        std::int32_t st = coag_sim_advance_to(s_.get(), t, &r);
        if (report) *report = r;
        if (st == COAG_INTERRUPTED) return false;
        check(st);
        return true;
    }
    /// Totals of every advance so far.
    coag_step_report totals() const {
        coag_step_report r = step_report();
        check(coag_sim_totals(s_.get(), &r));
        return r;
    }
    void set_work_limit(std::uint64_t units) { check(coag_sim_set_work_limit(s_.get(), units)); }
    void set_cancel_callback(coag_cancel_callback cb, void *user_data) {
        check(coag_sim_set_cancel_callback(s_.get(), cb, user_data));
    }
    void set_rng_callback(coag_rng_callback cb, void *user_data) {
        check(coag_sim_set_rng_callback(s_.get(), cb, user_data));
    }
    void reseed(std::uint64_t seed, std::uint64_t stream) { check(coag_sim_reseed(s_.get(), seed, stream)); }
    void set_dt(double dt) { check(coag_sim_set_dt(s_.get(), dt)); }
    void set_time(double t) { check(coag_sim_set_time(s_.get(), t)); }
    void set_mass(double mass) { check(coag_sim_set_mass(s_.get(), mass)); }
    void set_fragmentation(const Fragmentation *f) {
        check(coag_sim_set_fragmentation(s_.get(), f ? f->get() : nullptr));
    }
    coag_massflow_config massflow_config() const {
        coag_massflow_config c;
        check(coag_sim_massflow_config(s_.get(), &c, sizeof c));
        return c;
    }
    coag_eventflow_config eventflow_config() const {
        coag_eventflow_config c;
        check(coag_sim_eventflow_config(s_.get(), &c, sizeof c));
        return c;
    }
    coag_counts_config counts_config() const {
        coag_counts_config c;
        check(coag_sim_counts_config(s_.get(), &c, sizeof c));
        return c;
    }
    /// Occupied sizes (size-count sims) or particles (mass flow).
    std::size_t occupied() const {
        size_t n;
        check(coag_sim_occupied(s_.get(), &n));
        return n;
    }
    /// The occupied sizes and their counts, ascending (no dense vector).
    void pairs(std::vector<std::uint64_t> &sizes, std::vector<std::uint64_t> &counts,
               double *volume = nullptr) const {
        std::size_t n = occupied();
        sizes.resize(n);
        counts.resize(n);
        size_t written = 0;
        check(coag_sim_get_pairs(s_.get(), sizes.data(), counts.data(), n, volume, &written));
        sizes.resize(written);
        counts.resize(written);
    }
    void set_pairs(const std::vector<std::uint64_t> &sizes, const std::vector<std::uint64_t> &counts,
                   double volume) {
        if (sizes.size() != counts.size()) throw Error(COAG_INVALID_ARGUMENT, "pairs: sizes and counts differ in length");
        check(coag_sim_set_pairs(s_.get(), sizes.data(), counts.data(), sizes.size(), volume));
    }
    double time() const { return get(coag_sim_time); }
    /// The `COAG_METHOD_*` of a size-count sim (throws for a mass-flow sim).
    int method() const {
        std::int32_t m = -1;
        check(coag_sim_method(s_.get(), &m));
        return m;
    }
    /// The `COAG_BUCKET_SLOTS` or `_COUNTED` engine of a bucketed low-rank sim (throws
    /// for any other method).
    int bucket_mode() const {
        std::int32_t m = -1;
        check(coag_sim_bucket_mode(s_.get(), &m));
        return m;
    }
    double moment(double m) const {
        double v;
        check(coag_sim_moment(s_.get(), m, &v));
        return v;
    }
    double concentration(double a, double b) const {
        double v;
        check(coag_sim_concentration(s_.get(), a, b, &v));
        return v;
    }
    double gel_mass() const { return get(coag_sim_gel_mass); }
    std::uint64_t particle_count() const {
        std::uint64_t n;
        check(coag_sim_particle_count(s_.get(), &n));
        return n;
    }
    std::vector<double> sizes() const {
        std::vector<double> v(state_len());
        check(coag_sim_get_sizes(s_.get(), v.data(), v.size()));
        return v;
    }
    void set_sizes(const std::vector<double> &v) { check(coag_sim_set_sizes(s_.get(), v.data(), v.size())); }
    std::vector<std::uint64_t> counts(double *volume = nullptr) const {
        std::vector<std::uint64_t> v(state_len());
        check(coag_sim_get_counts(s_.get(), v.data(), v.size(), volume));
        return v;
    }
    void set_counts(const std::vector<std::uint64_t> &v, double volume) {
        check(coag_sim_set_counts(s_.get(), v.data(), v.size(), volume));
    }
    void set_kernel(const Kernel &k) { check(coag_sim_set_kernel(s_.get(), k.get())); }
    std::vector<std::uint8_t> checkpoint() const {
        size_t n;
        check(coag_sim_checkpoint_size(s_.get(), &n));
        std::vector<std::uint8_t> buf(n);
        check(coag_sim_checkpoint(s_.get(), buf.data(), buf.size(), &n));
        buf.resize(n);
        return buf;
    }
    void restore(const std::vector<std::uint8_t> &buf) { check(coag_sim_restore(s_.get(), buf.data(), buf.size())); }
    coag_sim *get() noexcept { return s_.get(); }
    std::size_t state_len() const {
        size_t n;
        check(coag_sim_state_len(s_.get(), &n));
        return n;
    }

  private:
    explicit Sim(coag_sim *s) : s_(s) {}
    double get(std::int32_t (*f)(const coag_sim *, double *)) const {
        double v;
        check(f(s_.get(), &v));
        return v;
    }
    std::unique_ptr<coag_sim, detail::SimFree> s_;
};

inline coag_langevin_config langevin_default_config() {
    coag_langevin_config c;
    check(coag_langevin_default_config(&c, sizeof c));
    return c;
}

/// Bytes of caller memory a Langevin batch of n trajectories needs (Langevin::make_in).
inline std::size_t langevin_workspace_size(const coag_langevin_config &c, std::uint64_t n) {
    size_t b;
    check(coag_langevin_workspace_size(&c, n, &b));
    return b;
}

/// Mean and standard error of an estimate over trajectories.
struct Estimate {
    double mean, std_error;
    std::uint64_t count;  // absorbed trajectories (Langevin::mean), or hits (first_hit_kernel)
};

/// A batch of Langevin trajectories with a specular or absorbing wall (Maftei et al.).
class Langevin {
  public:
    /// n trajectories from (x0, u0) (c.dim values each), trajectory i drawing from the
    /// generator (seed, first_id + i).
    static Langevin make(const coag_langevin_config &c, std::uint64_t n, const std::vector<double> &x0,
                         const std::vector<double> &u0, std::uint64_t seed, std::uint64_t first_id = 0) {
        coag_langevin *h = nullptr;
        check(coag_langevin_new(&c, n, x0.data(), u0.data(), seed, first_id, &h));
        return Langevin(h);
    }
    /// The same in caller-owned memory (bytes >= langevin_workspace_size, aligned for
    /// double), which must outlive the batch.
    static Langevin make_in(const coag_langevin_config &c, std::uint64_t n, const std::vector<double> &x0,
                            const std::vector<double> &u0, std::uint64_t seed, std::uint64_t first_id,
                            void *workspace, std::size_t bytes) {
        coag_langevin *h = nullptr;
        check(coag_langevin_new_in(&c, n, x0.data(), u0.data(), seed, first_id, workspace, bytes, &h));
        return Langevin(h);
    }
    coag_step_report advance_to(double t) {
        coag_step_report r = step_report();
        check(coag_langevin_advance_to(h_.get(), t, &r));
        return r;
    }
    double time() const {
        double t;
        check(coag_langevin_info(h_.get(), &t, nullptr, nullptr));
        return t;
    }
    std::size_t dim() const {
        std::size_t d;
        check(coag_langevin_info(h_.get(), nullptr, &d, nullptr));
        return d;
    }
    std::uint64_t size() const {
        std::uint64_t n;
        check(coag_langevin_info(h_.get(), nullptr, nullptr, &n));
        return n;
    }
    /// Positions (n·dim, trajectory-major).
    std::vector<double> positions() const {
        std::vector<double> x(size() * dim());
        check(coag_langevin_state(h_.get(), x.data(), nullptr, nullptr, nullptr, size()));
        return x;
    }
    /// Velocities (n·dim, trajectory-major).
    std::vector<double> velocities() const {
        std::vector<double> u(size() * dim());
        check(coag_langevin_state(h_.get(), nullptr, u.data(), nullptr, nullptr, size()));
        return u;
    }
    /// Wall hits of each trajectory.
    std::vector<std::uint64_t> hits() const {
        std::vector<std::uint64_t> k(size());
        check(coag_langevin_state(h_.get(), nullptr, nullptr, k.data(), nullptr, size()));
        return k;
    }
    /// Time of each trajectory's first hit (+inf when none).
    std::vector<double> first_hits() const {
        std::vector<double> t(size());
        check(coag_langevin_state(h_.get(), nullptr, nullptr, nullptr, t.data(), size()));
        return t;
    }
    /// Mean and SE of f(X, U) over the trajectories (f null: hits per trajectory);
    /// count = absorbed trajectories.
    Estimate mean(coag_observable_fn f = nullptr, void *user_data = nullptr) const {
        Estimate e{};
        check(coag_langevin_mean(h_.get(), f, user_data, &e.mean, &e.std_error, &e.count));
        return e;
    }
    std::vector<std::uint8_t> checkpoint() const {
        std::size_t n = 0;
        check(coag_langevin_checkpoint_size(h_.get(), &n));
        std::vector<std::uint8_t> buf(n);
        check(coag_langevin_save(h_.get(), buf.data(), buf.size(), &n));
        buf.resize(n);
        return buf;
    }
    void restore(const std::vector<std::uint8_t> &buf) { check(coag_langevin_restore(h_.get(), buf.data(), buf.size())); }
    coag_langevin *get() const noexcept { return h_.get(); }

  private:
    explicit Langevin(coag_langevin *h) : h_(h) {}
    static coag_step_report step_report() {
        coag_step_report r;
        check(coag_step_report_init(&r, sizeof r));
        return r;
    }
    std::unique_ptr<coag_langevin, detail::LangevinFree> h_;
};

/// The collision kernel from first hits (coag_first_hit_kernel); count = hits.
inline Estimate first_hit_kernel(const coag_first_hits &p, std::uint64_t seed, std::uint64_t first_id = 0) {
    Estimate e{};
    check(coag_first_hit_kernel(&p, seed, first_id, &e.mean, &e.std_error, &e.count));
    return e;
}

inline coag_thermal_config thermal_default_config() {
    coag_thermal_config c;
    check(coag_thermal_default_config(&c, sizeof c));
    return c;
}

/// The model family's closed form (coag_thermal_model_exact): {N(t), mean temperature}.
inline std::pair<double, double> thermal_model_exact(double c, double gamma, double n0, double t0, double t) {
    double n, tm;
    check(coag_thermal_model_exact(c, gamma, n0, t0, t, &n, &tm));
    return {n, tm};
}

/// Temperature-dependent low-rank Monte Carlo (Osinsky 2023 §4).
class Thermal {
  public:
    /// counts[i-1] = N_i particles of size i at temperature temperatures[i-1], in volume v.
    static Thermal make(const coag_thermal_config &c, const std::vector<std::uint64_t> &counts,
                        const std::vector<double> &temperatures, double volume) {
        if (counts.size() != temperatures.size()) check(COAG_INVALID_ARGUMENT);
        coag_thermal *h = nullptr;
        check(coag_thermal_new(&c, counts.data(), temperatures.data(), counts.size(), volume, &h));
        return Thermal(h);
    }
    coag_step_report advance_to(double t) {
        coag_step_report r;
        check(coag_step_report_init(&r, sizeof r));
        check(coag_thermal_advance_to(h_.get(), t, &r));
        return r;
    }
    double time() const {
        double t;
        check(coag_thermal_info(h_.get(), &t, nullptr, nullptr, nullptr));
        return t;
    }
    std::uint64_t particles() const {
        std::uint64_t n;
        check(coag_thermal_info(h_.get(), nullptr, &n, nullptr, nullptr));
        return n;
    }
    double volume() const {
        double v;
        check(coag_thermal_info(h_.get(), nullptr, nullptr, &v, nullptr));
        return v;
    }
    /// sum i^m N_i / V.
    double moment(double m) const {
        double v;
        check(coag_thermal_observe(h_.get(), m, &v, nullptr, nullptr));
        return v;
    }
    /// sum N_i T_i / N.
    double mean_temperature() const {
        double v;
        check(coag_thermal_observe(h_.get(), 0.0, nullptr, &v, nullptr));
        return v;
    }
    /// sum N_i T_i / V.
    double energy() const {
        double v;
        check(coag_thermal_observe(h_.get(), 0.0, nullptr, nullptr, &v));
        return v;
    }
    /// counts[i-1] = N_i for i = 1..max size.
    std::vector<std::uint64_t> counts() const {
        std::vector<std::uint64_t> c(max_size());
        check(coag_thermal_state(h_.get(), c.data(), nullptr, c.size()));
        return c;
    }
    /// temperatures[i-1] = T_i for i = 1..max size.
    std::vector<double> temperatures() const {
        std::vector<double> t(max_size());
        check(coag_thermal_state(h_.get(), nullptr, t.data(), t.size()));
        return t;
    }
    std::vector<std::uint8_t> checkpoint() const {
        std::size_t n = 0;
        check(coag_thermal_checkpoint_size(h_.get(), &n));
        std::vector<std::uint8_t> buf(n);
        check(coag_thermal_save(h_.get(), buf.data(), buf.size(), &n));
        buf.resize(n);
        return buf;
    }
    void restore(const std::vector<std::uint8_t> &buf) { check(coag_thermal_restore(h_.get(), buf.data(), buf.size())); }
    coag_thermal *get() const noexcept { return h_.get(); }

  private:
    explicit Thermal(coag_thermal *h) : h_(h) {}
    std::size_t max_size() const {
        std::size_t m;
        check(coag_thermal_info(h_.get(), nullptr, nullptr, nullptr, &m));
        return m;
    }
    std::unique_ptr<coag_thermal, detail::ThermalFree> h_;
};

inline coag_dsmc_config dsmc_default_config() {
    coag_dsmc_config c;
    check(coag_dsmc_default_config(&c, sizeof c));
    return c;
}

/// Low-rank DSMC (Osinsky 2023 §5): particles with 3-D velocities.
class Dsmc {
  public:
    /// Particles of sizes[p] with velocities[3p..3p+3], in volume v.
    static Dsmc make(const coag_dsmc_config &c, const std::vector<std::uint64_t> &sizes,
                     const std::vector<double> &velocities, double volume) {
        if (velocities.size() != 3 * sizes.size()) check(COAG_INVALID_ARGUMENT);
        coag_dsmc *h = nullptr;
        check(coag_dsmc_new(&c, sizes.data(), velocities.data(), sizes.size(), volume, &h));
        return Dsmc(h);
    }
    /// counts[i-1] Maxwellian particles of size i at temperature temperatures[i-1].
    static Dsmc maxwellian(const coag_dsmc_config &c, const std::vector<std::uint64_t> &counts,
                           const std::vector<double> &temperatures, double volume) {
        if (counts.size() != temperatures.size()) check(COAG_INVALID_ARGUMENT);
        coag_dsmc *h = nullptr;
        check(coag_dsmc_new_maxwellian(&c, counts.data(), temperatures.data(), counts.size(), volume, &h));
        return Dsmc(h);
    }
    coag_step_report advance_to(double t) {
        coag_step_report r;
        check(coag_step_report_init(&r, sizeof r));
        check(coag_dsmc_advance_to(h_.get(), t, &r));
        return r;
    }
    double time() const {
        double t;
        check(coag_dsmc_info(h_.get(), &t, nullptr, nullptr));
        return t;
    }
    std::uint64_t particles() const {
        std::uint64_t n;
        check(coag_dsmc_info(h_.get(), nullptr, &n, nullptr));
        return n;
    }
    double volume() const {
        double v;
        check(coag_dsmc_info(h_.get(), nullptr, nullptr, &v));
        return v;
    }
    std::vector<double> momentum() const {
        std::vector<double> p(3);
        check(coag_dsmc_observe(h_.get(), p.data(), nullptr, nullptr));
        return p;
    }
    double energy() const {
        double e;
        check(coag_dsmc_observe(h_.get(), nullptr, &e, nullptr));
        return e;
    }
    double mean_temperature() const {
        double t;
        check(coag_dsmc_observe(h_.get(), nullptr, nullptr, &t));
        return t;
    }
    /// The particles' sizes and velocities (3 per particle).
    std::pair<std::vector<std::uint64_t>, std::vector<double>> state() const {
        std::vector<std::uint64_t> s(particles());
        std::vector<double> v(3 * s.size());
        check(coag_dsmc_particles(h_.get(), s.data(), v.data(), s.size()));
        return {s, v};
    }
    std::vector<std::uint8_t> checkpoint() const {
        std::size_t n = 0;
        check(coag_dsmc_checkpoint_size(h_.get(), &n));
        std::vector<std::uint8_t> buf(n);
        check(coag_dsmc_save(h_.get(), buf.data(), buf.size(), &n));
        buf.resize(n);
        return buf;
    }
    void restore(const std::vector<std::uint8_t> &buf) { check(coag_dsmc_restore(h_.get(), buf.data(), buf.size())); }
    coag_dsmc *get() const noexcept { return h_.get(); }

  private:
    explicit Dsmc(coag_dsmc *h) : h_(h) {}
    std::unique_ptr<coag_dsmc, detail::DsmcFree> h_;
};

}  // namespace coagula

#endif
