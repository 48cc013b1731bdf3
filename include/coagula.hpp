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
    /// A size-count scheme: counts[i] particles of size i + 1.
    static Sim counts(const coag_counts_config &c, const Kernel &k, const std::vector<std::uint64_t> &counts) {
        coag_sim *s = nullptr;
        check(coag_counts_new(&c, k.get(), counts.data(), counts.size(), &s));
        return Sim(s);
    }

    coag_step_report advance_to(double t) {
        coag_step_report r;
        check(coag_step_report_init(&r, sizeof r));
        check(coag_sim_advance_to(s_.get(), t, &r));
        return r;
    }
    double time() const { return get(coag_sim_time); }
    /// The `COAG_METHOD_*` of a size-count sim (throws for a mass-flow sim).
    int method() const {
        std::int32_t m = -1;
        check(coag_sim_method(s_.get(), &m));
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

  private:
    explicit Sim(coag_sim *s) : s_(s) {}
    std::size_t state_len() const {
        size_t n;
        check(coag_sim_state_len(s_.get(), &n));
        return n;
    }
    double get(std::int32_t (*f)(const coag_sim *, double *)) const {
        double v;
        check(f(s_.get(), &v));
        return v;
    }
    std::unique_ptr<coag_sim, detail::SimFree> s_;
};

}  // namespace coagula

#endif
