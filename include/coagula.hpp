// coagula.hpp — header-only C++17 wrapper over the C ABI of libcoagula.
//
// RAII handles (move-only; clone() where the C ABI copies), exceptions from status
// codes (coagula::Error carries the code and the library's message), std::vector in
// and out. Same threading rules as the C API: one thread at a time per object.
//
// One Sim runs every population scheme of the registry, chosen by name
// (schemes() lists them with what each takes); Kernel::builtin builds core's
// built-in kernels by name and positional parameters (builtins() lists them);
// Options holds the settings by key (option_infos() lists the keys).
#ifndef COAGULA_HPP
#define COAGULA_HPP

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
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

/// The message of the last failed call on this thread.
inline std::string last_error_message() {
    size_t len = 0;
    if (coag_last_error_message(nullptr, 0, &len) != COAG_OK) return std::string();
    std::string msg(len + 1, '\0');
    coag_last_error_message(&msg[0], msg.size(), nullptr);
    msg.resize(len);
    return msg;
}

/// The name of a status code ("COAG_OK", ...).
inline std::string status_name(std::int32_t status) { return coag_status_name(status); }

/// Throws coagula::Error unless `status` is COAG_OK.
inline void check(std::int32_t status) {
    if (status == COAG_OK) return;
    throw Error(status, status_name(status) + ": " + last_error_message());
}

/// The library version.
inline std::string version() { return coag_version(); }

/// The change per class over a step, (after - before) / dt: a host's source terms.
inline std::vector<double> class_rates(const std::vector<double> &before, const std::vector<double> &after,
                                       double dt) {
    if (after.size() != before.size()) {
        throw Error(COAG_INVALID_ARGUMENT, "class_rates: before and after differ in length");
    }
    std::vector<double> out(before.size());
    check(coag_class_rates(before.data(), after.data(), before.size(), dt, out.data()));
    return out;
}

namespace detail {
inline std::string str(const char *p) { return p ? std::string(p) : std::string(); }
struct KernelFree {
    void operator()(coag_kernel *k) const noexcept { coag_kernel_free(k); }
};
struct FragFree {
    void operator()(coag_fragmentation *f) const noexcept { coag_fragmentation_free(f); }
};
struct OptionsFree {
    void operator()(coag_options *o) const noexcept { coag_options_free(o); }
};
struct SimFree {
    void operator()(coag_sim *s) const noexcept { coag_sim_free(s); }
};
struct LangevinFree {
    void operator()(coag_langevin *h) const noexcept { coag_langevin_free(h); }
};
template <class T>
bool negative(T v, std::true_type) { return v < T(0); }
template <class T>
bool negative(T, std::false_type) { return false; }
}  // namespace detail

// ---------------------------------------------------------------- core's tables

/// A registry scheme and its capabilities (coag_scheme_info_get).
struct SchemeInfo {
    std::size_t index = 0;
    std::string name, paper, summary;
    int model = 0;            ///< COAG_MODEL_*
    std::uint32_t inits = 0;  ///< COAG_INIT_* bits
    int sizes = 0;            ///< COAG_SAMPLES_*
    bool fragmentation = false;
    int memory = 0;  ///< COAG_MEMORY_*
    int law = 0;     ///< COAG_LAW_*
    std::uint64_t tag = 0;
    std::vector<std::string> options;      ///< the keys that apply besides seed and stream
    std::vector<std::string> observables;  ///< Sim::observable names
    bool takes(std::uint32_t init) const noexcept { return (inits & init) != 0; }
};

inline std::size_t scheme_count() {
    size_t n = 0;
    check(coag_scheme_count(&n));
    return n;
}
/// The index of the scheme named `name` (an unknown name throws COAG_INVALID_ARGUMENT).
inline std::size_t scheme_find(const std::string &name) {
    size_t i = 0;
    check(coag_scheme_find(name.c_str(), &i));
    return i;
}
inline SchemeInfo scheme_info(std::size_t index) {
    coag_scheme_info c{};
    check(coag_scheme_info_get(index, &c, sizeof c));
    SchemeInfo s;
    s.index = index;
    s.name = detail::str(c.name);
    s.paper = detail::str(c.paper);
    s.summary = detail::str(c.summary);
    s.model = c.model;
    s.inits = c.inits;
    s.sizes = c.sizes;
    s.fragmentation = c.fragmentation != 0;
    s.memory = c.memory;
    s.law = c.law;
    s.tag = c.tag;
    for (std::size_t i = 0; i < c.option_count; ++i) {
        const char *p = nullptr;
        check(coag_scheme_option(index, i, &p));
        s.options.push_back(detail::str(p));
    }
    for (std::size_t i = 0; i < c.observable_count; ++i) {
        const char *p = nullptr;
        check(coag_scheme_observable(index, i, &p));
        s.observables.push_back(detail::str(p));
    }
    return s;
}
inline SchemeInfo scheme_info(const std::string &name) { return scheme_info(scheme_find(name)); }
/// Every scheme of the registry.
inline std::vector<SchemeInfo> schemes() {
    std::vector<SchemeInfo> v;
    for (std::size_t i = 0, n = scheme_count(); i < n; ++i) v.push_back(scheme_info(i));
    return v;
}

/// An option key (coag_option_info_get).
struct OptionInfo {
    std::string name;
    int kind = 0;  ///< COAG_OPTION_*
    bool must_match = false;
    std::string default_value, doc;
};
inline std::size_t option_count() {
    size_t n = 0;
    check(coag_option_count(&n));
    return n;
}
inline OptionInfo option_info(std::size_t index) {
    coag_option_info c{};
    check(coag_option_info_get(index, &c, sizeof c));
    return OptionInfo{detail::str(c.name), c.kind, c.must_match != 0, detail::str(c.default_value),
                      detail::str(c.doc)};
}
/// Every option key.
inline std::vector<OptionInfo> option_infos() {
    std::vector<OptionInfo> v;
    for (std::size_t i = 0, n = option_count(); i < n; ++i) v.push_back(option_info(i));
    return v;
}

/// A parameter of a built-in kernel (coag_builtin_param).
struct ParamInfo {
    std::string name;
    bool has_default = false;
    double default_value = 0.0;  ///< NaN when required
    std::string unit, doc;
};
/// A built-in kernel (coag_builtin_info_get) with its parameters in Kernel::builtin's order.
struct BuiltinInfo {
    std::string name;
    int family = 0;  ///< COAG_FAMILY_*
    std::string formula, source, units;
    std::vector<ParamInfo> params;
};
inline std::size_t builtin_count() {
    size_t n = 0;
    check(coag_builtin_count(&n));
    return n;
}
inline BuiltinInfo builtin_info(std::size_t index) {
    coag_builtin_info c{};
    check(coag_builtin_info_get(index, &c, sizeof c));
    BuiltinInfo b{detail::str(c.name), c.family, detail::str(c.formula), detail::str(c.source),
                  detail::str(c.units), {}};
    for (std::size_t j = 0; j < c.param_count; ++j) {
        coag_param_info p{};
        check(coag_builtin_param(index, j, &p, sizeof p));
        b.params.push_back(
            ParamInfo{detail::str(p.name), p.has_default != 0, p.default_value, detail::str(p.unit), detail::str(p.doc)});
    }
    return b;
}
/// Every built-in kernel.
inline std::vector<BuiltinInfo> builtins() {
    std::vector<BuiltinInfo> v;
    for (std::size_t i = 0, n = builtin_count(); i < n; ++i) v.push_back(builtin_info(i));
    return v;
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

/// A zeroed step report with its struct_size set.
inline coag_step_report step_report() {
    coag_step_report r;
    check(coag_step_report_init(&r, sizeof r));
    return r;
}

// ---------------------------------------------------------------- handles

/// A kernel: a coagulation kernel, a temperature model or a gas (core's built-in
/// table), or a coagulation kernel from C callbacks.
class Kernel {
  public:
    /// Built-in kernel `name` with its parameters in the table's order (those past
    /// params.size() take their defaults; builtin_info lists them).
    static Kernel builtin(const std::string &name, const std::vector<double> &params = {}) {
        coag_kernel *k = nullptr;
        check(coag_kernel_new(name.c_str(), params.empty() ? nullptr : params.data(), params.size(), &k));
        return Kernel(k);
    }
    // Shorthands for builtin(name, params): parameters left out take the table's
    // defaults (the library's, not restated here).
    /// K = b.
    static Kernel constant() { return builtin("constant"); }
    static Kernel constant(double coefficient) { return builtin("constant", {coefficient}); }
    /// K = b (x + y), its bounds holding for sizes >= min_size.
    static Kernel additive() { return builtin("additive"); }
    static Kernel additive(double coefficient) { return builtin("additive", {coefficient}); }
    static Kernel additive(double coefficient, double min_size) { return builtin("additive", {coefficient, min_size}); }
    /// K = b x y.
    static Kernel multiplicative() { return builtin("multiplicative"); }
    static Kernel multiplicative(double coefficient) { return builtin("multiplicative", {coefficient}); }
    /// K = b (x y)^a.
    static Kernel product(double a) { return builtin("product", {a}); }
    static Kernel product(double a, double coefficient) { return builtin("product", {a, coefficient}); }
    /// A kernel from C callbacks (see coag_user_kernel); its callbacks and user_data
    /// must outlive every object made from it.
    static Kernel user(const coag_user_kernel &desc) {
        coag_kernel *k = nullptr;
        check(coag_kernel_new_user(&desc, &k));
        return Kernel(k);
    }

    /// A user kernel's supremum over blocks of sizes, for block majorants, and whether
    /// its low-rank bound is loose (see coag_kernel_set_user_blocks); sims made before
    /// keep what they had.
    Kernel &set_user_blocks(coag_block_sup_fn sup_block, bool low_rank_loose) {
        check(coag_kernel_set_user_blocks(k_.get(), sup_block, low_rank_loose ? 1 : 0));
        return *this;
    }

    /// K(x, y) of a coagulation kernel (COAG_UNSUPPORTED for a temperature model or a gas).
    double rate(double x, double y) const {
        double v;
        check(coag_kernel_rate(k_.get(), x, y, &v));
        return v;
    }
    const coag_kernel *get() const noexcept { return k_.get(); }

  private:
    explicit Kernel(coag_kernel *k) noexcept : k_(k) {}
    std::unique_ptr<coag_kernel, detail::KernelFree> k_;
};

/// A fragmentation kernel.
class Fragmentation {
  public:
    /// Binary break-up into two uniform pieces at rate lambda per particle.
    static Fragmentation binary_uniform(double lambda) {
        coag_fragmentation *f = nullptr;
        check(coag_fragmentation_new_binary_uniform(lambda, &f));
        return Fragmentation(f);
    }
    /// From C callbacks (see coag_user_fragmentation).
    static Fragmentation user(const coag_user_fragmentation &desc) {
        coag_fragmentation *f = nullptr;
        check(coag_fragmentation_new_user(&desc, &f));
        return Fragmentation(f);
    }
    const coag_fragmentation *get() const noexcept { return f_.get(); }

  private:
    explicit Fragmentation(coag_fragmentation *f) noexcept : f_(f) {}
    std::unique_ptr<coag_fragmentation, detail::FragFree> f_;
};

/// The settings a sim is built with, by key (option_infos() lists the keys; a key set
/// here that does not apply to the scheme makes the constructor throw COAG_UNSUPPORTED).
class Options {
  public:
    /// Every key at its default.
    Options() {
        coag_options *o = nullptr;
        check(coag_options_new(&o));
        o_.reset(o);
    }
    Options clone() const {
        coag_options *o = nullptr;
        check(coag_options_clone(o_.get(), &o));
        return Options(o);
    }
    /// A real (COAG_OPTION_REAL; a whole number also sets a count).
    Options &set(const std::string &key, double value) {
        check(coag_options_set_real(o_.get(), key.c_str(), value));
        return *this;
    }
    /// An integer (COAG_OPTION_COUNT; a negative one is refused by the library).
    template <class T, typename std::enable_if<std::is_integral<T>::value && !std::is_same<T, bool>::value,
                                               int>::type = 0>
    Options &set(const std::string &key, T value) {
        if (detail::negative(value, std::is_signed<T>()))
            check(coag_options_set_real(o_.get(), key.c_str(), static_cast<double>(value)));
        else
            check(coag_options_set_count(o_.get(), key.c_str(), static_cast<std::uint64_t>(value)));
        return *this;
    }
    /// On or off (COAG_OPTION_FLAG).
    Options &set(const std::string &key, bool value) {
        check(coag_options_set_flag(o_.get(), key.c_str(), value ? 1 : 0));
        return *this;
    }
    /// A name (COAG_OPTION_NAME).
    Options &set(const std::string &key, const std::string &value) {
        check(coag_options_set_name(o_.get(), key.c_str(), value.c_str()));
        return *this;
    }
    Options &set(const std::string &key, const char *value) { return set(key, std::string(value ? value : "")); }
    const coag_options *get() const noexcept { return o_.get(); }

  private:
    explicit Options(coag_options *o) noexcept : o_(o) {}
    std::unique_ptr<coag_options, detail::OptionsFree> o_;
};

/// The occupied sizes of a size-count sim and their counts (Sim::pairs).
struct Pairs {
    std::vector<std::uint64_t> sizes, counts;
    double volume = 0.0;
};
/// A per-size quantity for every occupied size (Sim::size_values).
struct SizeValues {
    std::vector<std::uint64_t> sizes;
    std::vector<double> values;
};
/// The particles of a gas: sizes and velocities, 3 per particle (Sim::particles).
struct Particles {
    std::vector<std::uint64_t> sizes;
    std::vector<double> velocities;
};

/// A simulation of any registry scheme, stepped with advance_to. The optional
/// Options and Fragmentation (nullptr: defaults, none) may be freed after construction.
class Sim {
  public:
    /// counts[i] particles of size i + 1 in `volume` (COAG_INIT_COUNTS).
    static Sim from_counts(const std::string &scheme, const Kernel &k, const std::vector<std::uint64_t> &counts,
                           double volume, const Options *o = nullptr, const Fragmentation *f = nullptr) {
        coag_sim *s = nullptr;
        check(coag_sim_new_counts(scheme.c_str(), k.get(), frag(f), opts(o), counts.data(), counts.size(), volume, &s));
        return Sim(s);
    }
    /// Particle sizes carrying the mass `mass` (COAG_INIT_SIZES; SchemeInfo::sizes
    /// says whether they sample the mass or the number distribution).
    static Sim from_sizes(const std::string &scheme, const Kernel &k, const std::vector<double> &sizes, double mass,
                          const Options *o = nullptr, const Fragmentation *f = nullptr) {
        coag_sim *s = nullptr;
        check(coag_sim_new_sizes(scheme.c_str(), k.get(), frag(f), opts(o), sizes.data(), sizes.size(), mass, &s));
        return Sim(s);
    }
    /// Bytes of caller workspace from_sizes_in needs for n sizes (COAG_MEMORY_FIXED
    /// schemes; COAG_UNSUPPORTED for the others).
    static std::size_t workspace_size(const std::string &scheme, std::size_t n, const Options *o = nullptr,
                                      const Fragmentation *f = nullptr) {
        size_t b = 0;
        check(coag_sim_workspace_size(scheme.c_str(), frag(f), opts(o), n, &b));
        return b;
    }
    /// from_sizes in caller-owned memory (bytes >= workspace_size, aligned for double),
    /// which must outlive the Sim and is zeroed first.
    static Sim from_sizes_in(const std::string &scheme, const Kernel &k, const std::vector<double> &sizes,
                             double mass, void *workspace, std::size_t bytes, const Options *o = nullptr,
                             const Fragmentation *f = nullptr) {
        coag_sim *s = nullptr;
        check(coag_sim_new_sizes_in(scheme.c_str(), k.get(), frag(f), opts(o), sizes.data(), sizes.size(), mass,
                                    workspace, bytes, &s));
        return Sim(s);
    }
    /// counts[i] particles of size i + 1 at partial temperature temperatures[i]
    /// (COAG_INIT_TEMPERATURES, under a temperature model).
    static Sim from_temperatures(const std::string &scheme, const Kernel &k, const std::vector<std::uint64_t> &counts,
                                 const std::vector<double> &temperatures, double volume, const Options *o = nullptr) {
        if (counts.size() != temperatures.size())
            throw Error(COAG_BUFFER_TOO_SMALL, "from_temperatures: counts and temperatures differ in length");
        coag_sim *s = nullptr;
        check(coag_sim_new_temperatures(scheme.c_str(), k.get(), opts(o), counts.data(), temperatures.data(),
                                        counts.size(), volume, &s));
        return Sim(s);
    }
    /// Particle p of size sizes[p] with velocity velocities[3p .. 3p + 3]
    /// (COAG_INIT_VELOCITIES, under a gas).
    static Sim from_velocities(const std::string &scheme, const Kernel &k, const std::vector<std::uint64_t> &sizes,
                               const std::vector<double> &velocities, double volume, const Options *o = nullptr) {
        if (velocities.size() != 3 * sizes.size())
            throw Error(COAG_BUFFER_TOO_SMALL, "from_velocities: velocities must hold 3 values per particle");
        coag_sim *s = nullptr;
        check(coag_sim_new_velocities(scheme.c_str(), k.get(), opts(o), sizes.data(), velocities.data(), sizes.size(),
                                      volume, &s));
        return Sim(s);
    }
    /// counts[i] particles of size i + 1 with Maxwellian velocities at temperatures[i],
    /// drawn from the options' seed and stream (COAG_INIT_VELOCITIES).
    static Sim from_maxwellian(const std::string &scheme, const Kernel &k, const std::vector<std::uint64_t> &counts,
                               const std::vector<double> &temperatures, double volume, const Options *o = nullptr) {
        if (counts.size() != temperatures.size())
            throw Error(COAG_BUFFER_TOO_SMALL, "from_maxwellian: counts and temperatures differ in length");
        coag_sim *s = nullptr;
        check(coag_sim_new_maxwellian(scheme.c_str(), k.get(), opts(o), counts.data(), temperatures.data(),
                                      counts.size(), volume, &s));
        return Sim(s);
    }
    /// An exact, independent copy (in memory the library owns).
    Sim clone() const {
        coag_sim *s = nullptr;
        check(coag_sim_clone(s_.get(), &s));
        return Sim(s);
    }

    /// The registry name of the sim's scheme.
    std::string scheme() const { return name_of(coag_sim_scheme); }
    /// The engine of the bucketed low-rank scheme ("slots" or "counted"; throws
    /// COAG_UNSUPPORTED for any other scheme).
    std::string engine() const { return name_of(coag_sim_engine); }

    /// Runs to t; a call stopped by its work limit or cancellation throws coagula::Error
    /// with code COAG_INTERRUPTED (see advance_within to continue instead).
    coag_step_report advance_to(double t) {
        coag_step_report r = step_report();
        check(coag_sim_advance_to(s_.get(), t, &r));
        return r;
    }
    /// Runs towards t; false when the work limit or the cancellation callback stopped
    /// the call (the sim is consistent at report->time; call again), true when t was
    /// reached. Errors throw.
    bool advance_within(double t, coag_step_report *report = nullptr) {
        coag_step_report r = step_report();
        std::int32_t st = coag_sim_advance_to(s_.get(), t, &r);
        if (st == COAG_INTERRUPTED) {
            if (report) *report = r;
            return false;
        }
        check(st);
        if (report) *report = r;
        return true;
    }
    /// Totals of every advance so far.
    coag_step_report totals() const {
        coag_step_report r = step_report();
        check(coag_sim_totals(s_.get(), &r));
        return r;
    }
    void set_work_limit(std::uint64_t units) { check(coag_sim_set_work_limit(s_.get(), units)); }
    /// cb (nullptr removes it) must not throw; it and user_data must stay valid while installed.
    void set_cancel_callback(coag_cancel_callback cb, void *user_data) {
        check(coag_sim_set_cancel_callback(s_.get(), cb, user_data));
    }
    /// Draws from cb (nullptr: the sim's own stream again); must not throw.
    void set_rng_callback(coag_rng_callback cb, void *user_data) {
        check(coag_sim_set_rng_callback(s_.get(), cb, user_data));
    }
    void reseed(std::uint64_t seed, std::uint64_t stream) { check(coag_sim_reseed(s_.get(), seed, stream)); }

    /// The full state, own random stream included.
    std::vector<std::uint8_t> checkpoint() const {
        size_t n = 0;
        check(coag_sim_checkpoint_size(s_.get(), &n));
        std::vector<std::uint8_t> buf(n);
        check(coag_sim_checkpoint(s_.get(), buf.data(), buf.size(), &n));
        buf.resize(n);
        return buf;
    }
    /// Restores a checkpoint of a sim of the same scheme, settings and physics.
    void restore(const std::vector<std::uint8_t> &buf) { check(coag_sim_restore(s_.get(), buf.data(), buf.size())); }

    double time() const { return real(coag_sim_time); }
    double moment(double m) const {
        double v;
        check(coag_sim_moment(s_.get(), m, &v));
        return v;
    }
    /// Number concentration of sizes in [a, b].
    double concentration(double a, double b) const {
        double v;
        check(coag_sim_concentration(s_.get(), a, b, &v));
        return v;
    }
    /// Number concentrations of the half-open classes [edges[i], edges[i+1]).
    std::vector<double> class_concentrations(const std::vector<double> &edges) const {
        std::vector<double> v(edges.size() > 1 ? edges.size() - 1 : 0);
        check(coag_sim_class_concentrations(s_.get(), edges.data(), edges.size(), v.data()));
        return v;
    }
    double gel_mass() const { return real(coag_sim_gel_mass); }
    /// A named observable of the scheme (SchemeInfo::observables).
    double observable(const std::string &name) const {
        double v;
        check(coag_sim_observable(s_.get(), name.c_str(), &v));
        return v;
    }
    std::uint64_t particle_count() const {
        std::uint64_t n;
        check(coag_sim_particle_count(s_.get(), &n));
        return n;
    }
    /// Particles (sims over sizes) or the largest occupied size (size-count sims).
    std::size_t state_len() const {
        size_t n;
        check(coag_sim_state_len(s_.get(), &n));
        return n;
    }
    /// Occupied sizes (size-count sims) or particles (sims over sizes).
    std::size_t occupied() const {
        size_t n;
        check(coag_sim_occupied(s_.get(), &n));
        return n;
    }
    /// The occupied sizes and their counts, ascending (no dense vector), and the volume.
    Pairs pairs() const {
        Pairs p;
        std::size_t n = occupied();
        p.sizes.resize(n);
        p.counts.resize(n);
        size_t written = 0;
        check(coag_sim_get_pairs(s_.get(), p.sizes.data(), p.counts.data(), n, &p.volume, &written));
        p.sizes.resize(written);
        p.counts.resize(written);
        return p;
    }
    /// The particle sizes of a sim over sizes.
    std::vector<double> sizes() const {
        std::vector<double> v(state_len());
        check(coag_sim_get_sizes(s_.get(), v.data(), v.size()));
        return v;
    }
    /// The dense counts (v[i]: size i + 1) of a size-count sim; its volume to *volume.
    std::vector<std::uint64_t> counts(double *volume = nullptr) const {
        std::vector<std::uint64_t> v(state_len());
        check(coag_sim_get_counts(s_.get(), v.data(), v.size(), volume));
        return v;
    }
    /// A per-size quantity by name ("temperature") for every occupied size.
    SizeValues size_values(const std::string &name) const {
        SizeValues r;
        std::size_t n = occupied();
        r.sizes.resize(n);
        r.values.resize(n);
        size_t written = 0;
        check(coag_sim_size_values(s_.get(), name.c_str(), r.sizes.data(), r.values.data(), n, &written));
        r.sizes.resize(written);
        r.values.resize(written);
        return r;
    }
    /// The particles of a gas.
    Particles particles() const {
        Particles p;
        std::uint64_t n = particle_count();
        p.sizes.resize(static_cast<std::size_t>(n));
        p.velocities.resize(3 * p.sizes.size());
        check(coag_sim_velocities(s_.get(), p.sizes.data(), p.velocities.data(), p.sizes.size()));
        return p;
    }

    void set_pairs(const Pairs &p) {
        if (p.sizes.size() != p.counts.size())
            throw Error(COAG_BUFFER_TOO_SMALL, "set_pairs: sizes and counts differ in length");
        check(coag_sim_set_pairs(s_.get(), p.sizes.data(), p.counts.data(), p.sizes.size(), p.volume));
    }
    void set_sizes(const std::vector<double> &v) { check(coag_sim_set_sizes(s_.get(), v.data(), v.size())); }
    void set_counts(const std::vector<std::uint64_t> &v, double volume) {
        check(coag_sim_set_counts(s_.get(), v.data(), v.size(), volume));
    }
    void set_kernel(const Kernel &k) { check(coag_sim_set_kernel(s_.get(), k.get())); }
    /// nullptr: no fragmentation.
    void set_fragmentation(const Fragmentation *f) { check(coag_sim_set_fragmentation(s_.get(), frag(f))); }
    void set_dt(double dt) { check(coag_sim_set_dt(s_.get(), dt)); }
    void set_time(double t) { check(coag_sim_set_time(s_.get(), t)); }
    void set_mass(double mass) { check(coag_sim_set_mass(s_.get(), mass)); }
    /// Processes beside coagulation (see coagula.h): kind is a COAG_SOURCE_* constant.
    void set_source(double rate, std::int32_t kind, double p1, double p2 = 0.0) {
        check(coag_sim_set_source(s_.get(), rate, kind, p1, p2));
    }
    /// A source drawing its sizes uniformly from a list (a mixture).
    void set_source_sizes(double rate, const std::vector<double> &sizes) {
        check(coag_sim_set_source_sizes(s_.get(), rate, sizes.data(), sizes.size()));
    }
    /// The source's rate as a piecewise-constant schedule (set a source first).
    void set_source_schedule(const std::vector<double> &times, const std::vector<double> &rates) {
        if (times.size() != rates.size()) {
            throw Error(COAG_INVALID_ARGUMENT, "set_source_schedule: as many rates as times");
        }
        check(coag_sim_set_source_schedule(s_.get(), times.data(), rates.data(), times.size()));
    }
    /// A host's removal / growth rate per particle, at most `bound` at every size
    /// (nullptr: none); `tag` names it in checkpoints.
    void set_source_callback(coag_rate_callback rate, void *user_data, double bound, std::uint64_t tag = 0) {
        check(coag_sim_set_source_callback(s_.get(), rate, user_data, bound, tag));
    }
    void set_removal_callback(coag_rate_callback rate, void *user_data, double bound, std::uint64_t tag = 0) {
        check(coag_sim_set_removal_callback(s_.get(), rate, user_data, bound, tag));
    }
    void set_growth_callback(coag_rate_callback rate, void *user_data, double bound, std::uint64_t tag = 0) {
        check(coag_sim_set_growth_callback(s_.get(), rate, user_data, bound, tag));
    }
    void set_removal(double coefficient, double exponent) {
        check(coag_sim_set_removal(s_.get(), coefficient, exponent));
    }
    void set_growth(double coefficient, double exponent) {
        check(coag_sim_set_growth(s_.get(), coefficient, exponent));
    }
    /// The splitting step of growth on real sizes (set it before the growth).
    void set_growth_step(double step) { check(coag_sim_set_growth_step(s_.get(), step)); }
    void clear_processes() { check(coag_sim_clear_processes(s_.get())); }
    /// The processes' books (throws COAG_UNSUPPORTED when none is set).
    coag_books books() const {
        coag_books b{};
        b.struct_size = sizeof b;
        check(coag_sim_books(s_.get(), &b));
        return b;
    }

    /// The population on a host's size classes (number and mass kept); the returned
    /// array is {N_below, M_below, N_above, M_above}, what lies outside the pivots.
    std::array<double, 4> project(const std::vector<double> &pivots, std::vector<double> &numbers) const {
        numbers.resize(pivots.size());
        std::array<double, 4> outside{};
        check(coag_sim_project(s_.get(), pivots.data(), pivots.size(), numbers.data(), outside.data()));
        return outside;
    }
    /// Replaces the population by class numbers per unit volume at the pivots.
    void set_classes(const std::vector<double> &pivots, const std::vector<double> &numbers) {
        if (numbers.size() != pivots.size()) {
            throw Error(COAG_INVALID_ARGUMENT, "set_classes: as many numbers as pivots");
        }
        check(coag_sim_set_classes(s_.get(), pivots.data(), numbers.data(), pivots.size()));
    }

    coag_sim *get() noexcept { return s_.get(); }
    const coag_sim *get() const noexcept { return s_.get(); }

  private:
    explicit Sim(coag_sim *s) noexcept : s_(s) {}
    static const coag_fragmentation *frag(const Fragmentation *f) noexcept { return f ? f->get() : nullptr; }
    static const coag_options *opts(const Options *o) noexcept { return o ? o->get() : nullptr; }
    double real(std::int32_t (*f)(const coag_sim *, double *)) const {
        double v;
        check(f(s_.get(), &v));
        return v;
    }
    std::string name_of(std::int32_t (*f)(const coag_sim *, const char **)) const {
        const char *p = nullptr;
        check(f(s_.get(), &p));
        return detail::str(p);
    }
    std::unique_ptr<coag_sim, detail::SimFree> s_;
};

// ---------------------------------------------------------------- Langevin

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
        check_start(c, x0, u0);
        coag_langevin *h = nullptr;
        check(coag_langevin_new(&c, n, x0.data(), u0.data(), seed, first_id, &h));
        return Langevin(h);
    }
    /// The same in caller-owned memory (bytes >= langevin_workspace_size, aligned for
    /// double), which must outlive the batch.
    static Langevin make_in(const coag_langevin_config &c, std::uint64_t n, const std::vector<double> &x0,
                            const std::vector<double> &u0, std::uint64_t seed, std::uint64_t first_id,
                            void *workspace, std::size_t bytes) {
        check_start(c, x0, u0);
        coag_langevin *h = nullptr;
        check(coag_langevin_new_in(&c, n, x0.data(), u0.data(), seed, first_id, workspace, bytes, &h));
        return Langevin(h);
    }
    /// An exact, independent copy (in memory the library owns).
    Langevin clone() const {
        coag_langevin *h = nullptr;
        check(coag_langevin_clone(h_.get(), &h));
        return Langevin(h);
    }
    /// Steps to t; a stopped call throws COAG_INTERRUPTED (see advance_within).
    coag_step_report advance_to(double t) {
        coag_step_report r = step_report();
        check(coag_langevin_advance_to(h_.get(), t, &r));
        return r;
    }
    /// Steps towards t; false when the work limit or the cancellation callback stopped it.
    bool advance_within(double t, coag_step_report *report = nullptr) {
        coag_step_report r = step_report();
        std::int32_t st = coag_langevin_advance_to(h_.get(), t, &r);
        if (st != COAG_INTERRUPTED) check(st);
        if (report) *report = r;
        return st == COAG_OK;
    }
    void set_work_limit(std::uint64_t units) { check(coag_langevin_set_work_limit(h_.get(), units)); }
    /// cb (nullptr removes it) must not throw.
    void set_cancel_callback(coag_cancel_callback cb, void *user_data) {
        check(coag_langevin_set_cancel_callback(h_.get(), cb, user_data));
    }
    double time() const {
        double t;
        check(coag_langevin_info(h_.get(), &t, nullptr, nullptr));
        return t;
    }
    std::size_t dim() const {
        size_t d;
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
        std::vector<double> x(len() * dim());
        check(coag_langevin_state(h_.get(), x.data(), nullptr, nullptr, nullptr, len()));
        return x;
    }
    /// Velocities (n·dim, trajectory-major).
    std::vector<double> velocities() const {
        std::vector<double> u(len() * dim());
        check(coag_langevin_state(h_.get(), nullptr, u.data(), nullptr, nullptr, len()));
        return u;
    }
    /// Wall hits of each trajectory.
    std::vector<std::uint64_t> hits() const {
        std::vector<std::uint64_t> k(len());
        check(coag_langevin_state(h_.get(), nullptr, nullptr, k.data(), nullptr, k.size()));
        return k;
    }
    /// Time of each trajectory's first hit (+inf when none).
    std::vector<double> first_hits() const {
        std::vector<double> t(len());
        check(coag_langevin_state(h_.get(), nullptr, nullptr, nullptr, t.data(), t.size()));
        return t;
    }
    /// Mean and SE of f(X, U) over the trajectories (f null: hits per trajectory);
    /// count = absorbed trajectories. f must not throw.
    Estimate mean(coag_observable_fn f = nullptr, void *user_data = nullptr) const {
        Estimate e{};
        check(coag_langevin_mean(h_.get(), f, user_data, &e.mean, &e.std_error, &e.count));
        return e;
    }
    std::vector<std::uint8_t> checkpoint() const {
        size_t n = 0;
        check(coag_langevin_checkpoint_size(h_.get(), &n));
        std::vector<std::uint8_t> buf(n);
        check(coag_langevin_save(h_.get(), buf.data(), buf.size(), &n));
        buf.resize(n);
        return buf;
    }
    void restore(const std::vector<std::uint8_t> &buf) { check(coag_langevin_restore(h_.get(), buf.data(), buf.size())); }
    coag_langevin *get() const noexcept { return h_.get(); }

  private:
    explicit Langevin(coag_langevin *h) noexcept : h_(h) {}
    static void check_start(const coag_langevin_config &c, const std::vector<double> &x0, const std::vector<double> &u0) {
        if (x0.size() != c.dim || u0.size() != c.dim)
            throw Error(COAG_BUFFER_TOO_SMALL, "Langevin: x0 and u0 must hold config.dim values");
    }
    std::size_t len() const { return static_cast<std::size_t>(size()); }
    std::unique_ptr<coag_langevin, detail::LangevinFree> h_;
};

/// Core's sectional reference (fixed pivot, Kumar & Ramkrishna 1996) on a host's
/// pivots: coagulation with a source at one size, removal and growth at powers of size.
class Sectional {
  public:
    Sectional(const Kernel &k, const std::vector<double> &pivots) {
        coag_sectional *s = nullptr;
        check(coag_sectional_new(k.get(), pivots.data(), pivots.size(), &s));
        s_.reset(s);
        len_ = pivots.size();
    }
    void set_processes(double source_rate, double source_size, double removal_coefficient, double removal_exponent,
                       double growth_coefficient, double growth_exponent) {
        check(coag_sectional_set_processes(s_.get(), source_rate, source_size, removal_coefficient, removal_exponent,
                                           growth_coefficient, growth_exponent));
    }
    void set_numbers(const std::vector<double> &n) { check(coag_sectional_set_numbers(s_.get(), n.data(), n.size())); }
    void add(double size, double number) { check(coag_sectional_add(s_.get(), size, number)); }
    void advance_to(double t, double dt) { check(coag_sectional_advance_to(s_.get(), t, dt)); }
    std::vector<double> numbers() const {
        std::vector<double> n(len_);
        check(coag_sectional_numbers(s_.get(), n.data(), n.size()));
        return n;
    }
    double moment(double order) const {
        double m = 0.0;
        check(coag_sectional_moment(s_.get(), order, &m, nullptr));
        return m;
    }
    double time() const {
        double t = 0.0;
        check(coag_sectional_moment(s_.get(), 0.0, nullptr, &t));
        return t;
    }
    coag_sectional *get() const noexcept { return s_.get(); }

  private:
    struct Free {
        void operator()(coag_sectional *s) const noexcept { coag_sectional_free(s); }
    };
    std::unique_ptr<coag_sectional, Free> s_;
    std::size_t len_ = 0;
};

/// The collision kernel from first hits (coag_first_hit_kernel); count = hits.
inline Estimate first_hit_kernel(const coag_first_hits &p, std::uint64_t seed, std::uint64_t first_id = 0) {
    Estimate e{};
    check(coag_first_hit_kernel(&p, seed, first_id, &e.mean, &e.std_error, &e.count));
    return e;
}

}  // namespace coagula

#endif
