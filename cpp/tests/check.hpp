#pragma once
/// The runner of the core's C++ unit tests: a few macros, no dependency.
///
///     TEST_CASE("gjk: boxes one apart") {
///         REQUIRE(result.status == Status::CONVERGED);   // stops this test case when false
///         CHECK_NEAR(result.distance, 1.0, 1e-12);        // records, then goes on
///     }
///
/// Test cases register themselves (a static object per case); main.cpp runs them all, or
/// those whose name contains its first argument, prints each failure as `file:line: ...` and
/// ends with one line `N passed, N failed` (test cases); the exit status is 1 when one failed.
/// An exception escaping a test case fails it with its message.

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

namespace meshcol::check {

struct TestCase {
    const char* name;
    void (*run)();
    const char* file;
    int line;
};

/// Every registered test case, in registration order (per file, files in link order).
inline std::vector<TestCase>& registry() {
    static std::vector<TestCase> cases;
    return cases;
}

struct Registration {
    Registration(const char* name, void (*run)(), const char* file, int line) {
        registry().push_back({name, run, file, line});
    }
};

/// Thrown by REQUIRE to end the current test case (caught by the runner only).
struct RequireFailed {};

/// Failures recorded in the running test case.
inline int& failures() {
    static int count = 0;
    return count;
}

inline void fail(const char* file, int line, const std::string& what) {
    std::fprintf(stderr, "%s:%d: FAILED: %s\n", file, line, what.c_str());
    ++failures();
}

template <class T>
std::string show(const T& value) {
    std::ostringstream text;
    text.precision(17);
    text << value;
    return text.str();
}

inline bool near(double actual, double expected, double tolerance) {
    return std::fabs(actual - expected) <= tolerance;  // false for NaN
}

}  // namespace meshcol::check

#define MESHCOL_CHECK_JOIN2(a, b) a##b
#define MESHCOL_CHECK_JOIN(a, b) MESHCOL_CHECK_JOIN2(a, b)
#define MESHCOL_TEST_CASE_AT(name, id)                                                       \
    static void MESHCOL_CHECK_JOIN(meshcol_test_, id)();                                     \
    static const ::meshcol::check::Registration MESHCOL_CHECK_JOIN(meshcol_registration_, id)( \
        name, &MESHCOL_CHECK_JOIN(meshcol_test_, id), __FILE__, __LINE__);                   \
    static void MESHCOL_CHECK_JOIN(meshcol_test_, id)()

/// Defines and registers a test case named `name` (a string literal).
#define TEST_CASE(name) MESHCOL_TEST_CASE_AT(name, __COUNTER__)

/// Records a failure when `condition` is false and goes on.
#define CHECK(condition)                                                         \
    do {                                                                         \
        if (!(condition)) ::meshcol::check::fail(__FILE__, __LINE__, #condition); \
    } while (false)

/// Records a failure when `condition` is false and ends the test case.
#define REQUIRE(condition)                                                       \
    do {                                                                         \
        if (!(condition)) {                                                      \
            ::meshcol::check::fail(__FILE__, __LINE__, #condition);              \
            throw ::meshcol::check::RequireFailed{};                             \
        }                                                                        \
    } while (false)

/// Records a failure, with both values, when `actual == expected` is false.
#define CHECK_EQ(actual, expected)                                                            \
    do {                                                                                      \
        const auto& meshcol_actual = (actual);                                                \
        const auto& meshcol_expected = (expected);                                            \
        if (!(meshcol_actual == meshcol_expected))                                            \
            ::meshcol::check::fail(__FILE__, __LINE__,                                        \
                                   std::string(#actual " == " #expected ": ") +               \
                                       ::meshcol::check::show(meshcol_actual) + " != " +      \
                                       ::meshcol::check::show(meshcol_expected));             \
    } while (false)

/// Records a failure, with both values, when |actual - expected| > tolerance (or NaN).
#define CHECK_NEAR(actual, expected, tolerance)                                                \
    do {                                                                                       \
        const double meshcol_actual = (actual);                                                \
        const double meshcol_expected = (expected);                                            \
        if (!::meshcol::check::near(meshcol_actual, meshcol_expected, (tolerance)))            \
            ::meshcol::check::fail(__FILE__, __LINE__,                                         \
                                   std::string(#actual " ~= " #expected ": ") +                \
                                       ::meshcol::check::show(meshcol_actual) + " vs " +       \
                                       ::meshcol::check::show(meshcol_expected) + " (+- " +    \
                                       ::meshcol::check::show(tolerance) + ")");               \
    } while (false)

/// Records a failure unless evaluating `expression` throws an `exception_type`.
#define CHECK_THROWS_AS(expression, exception_type)                                          \
    do {                                                                                     \
        bool meshcol_thrown = false;                                                         \
        try {                                                                                \
            (void)(expression);                                                              \
        } catch (const exception_type&) {                                                    \
            meshcol_thrown = true;                                                           \
        } catch (...) {                                                                      \
        }                                                                                    \
        if (!meshcol_thrown)                                                                 \
            ::meshcol::check::fail(__FILE__, __LINE__, #expression " throws " #exception_type); \
    } while (false)
