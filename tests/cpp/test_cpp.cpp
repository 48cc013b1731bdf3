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
    std::printf("test_cpp: %d passed, %d failed\n", checks - failures, failures);
    return failures ? 1 : 0;
}
