// Runs the registered test cases (check.hpp): all of them, or those whose name contains the
// first argument; prints each failure, then `N passed, N failed`.
#include <cstdio>
#include <cstring>
#include <exception>

#include "check.hpp"

int main(int argc, char** argv) {
    const char* filter = argc > 1 ? argv[1] : "";
    int passed = 0, failed = 0;
    for (const auto& test : meshcol::check::registry()) {
        if (std::strstr(test.name, filter) == nullptr) continue;
        meshcol::check::failures() = 0;
        try {
            test.run();
        } catch (const meshcol::check::RequireFailed&) {
            // recorded where it happened
        } catch (const std::exception& e) {
            meshcol::check::fail(test.file, test.line, std::string("unexpected exception: ") + e.what());
        } catch (...) {
            meshcol::check::fail(test.file, test.line, "unexpected exception");
        }
        if (meshcol::check::failures() == 0) {
            ++passed;
        } else {
            ++failed;
            std::fprintf(stderr, "%s:%d: test case failed: %s\n", test.file, test.line, test.name);
        }
    }
    std::printf("%d passed, %d failed\n", passed, failed);
    return failed == 0 && passed > 0 ? 0 : 1;
}
