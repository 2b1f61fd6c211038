// The report writer's rows (report_rows.hpp): the list written into a file descriptor on
// several threads is the text written into memory, and a write that fails stops it with its
// errno.
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "check.hpp"
#include "meshcol/report_rows.hpp"

using namespace meshcol;

namespace {

struct Table {
    std::vector<double> numbers, vectors;
    std::vector<std::int64_t> codes;
    std::unique_ptr<bool[]> flags;
};

/// Rows of a number, a vector, a string and a flag; the string table has one entry of
/// `long_entry` chars (row 1 only), which makes a row's bound, and so a block, large.
RowWriter writer_of(Table& t, std::size_t n, std::size_t long_entry) {
    t.numbers.resize(n);
    t.vectors.resize(3 * n);
    t.codes.resize(n);
    t.flags.reset(new bool[n == 0 ? 1 : n]);
    for (std::size_t i = 0; i < n; ++i) {
        t.numbers[i] = i % 7 == 3 ? std::numeric_limits<double>::quiet_NaN() : 0.37 * i - 5e-7;
        for (int k = 0; k < 3; ++k) t.vectors[3 * i + k] = std::ldexp(1.0 + i, k - 30);
        t.codes[i] = i == 1 ? 1 : static_cast<std::int64_t>(i % 3) - 1;
        t.flags[i] = i % 2 == 0;
    }
    std::vector<RowColumn> columns(4);
    columns[0].kind = RowColumn::kBoolean, columns[0].key = "\"flag\"", columns[0].flags = t.flags.get();
    columns[1].kind = RowColumn::kNumber, columns[1].key = "\"number\"", columns[1].reals = t.numbers.data();
    columns[2].kind = RowColumn::kString, columns[2].key = "\"string\"", columns[2].integers = t.codes.data();
    columns[2].table = std::make_shared<const std::vector<std::string>>(
        std::vector<std::string>{"\"a\"", "\"" + std::string(long_entry, 'x') + "\""});
    columns[3].kind = RowColumn::kVector, columns[3].key = "\"vector\"", columns[3].reals = t.vectors.data();
    return RowWriter(std::move(columns), 1);
}

std::string in_memory(const RowWriter& w, std::size_t n) {
    if (n == 0) return "[]";
    std::string text(n * w.row_bound() + 1, '\0');
    text[0] = '[';
    char* end = w.write(0, n, text.data() + 1);
    text.resize(static_cast<std::size_t>(end - text.data()));
    return text + "\n  ]";
}

std::string through_file(const RowWriter& w, std::size_t n, int threads, int* failed) {
    std::FILE* file = std::tmpfile();
    const int fd = fileno(file);
    *failed = w.write_to(fd, n, threads);
    std::string text;
    ::lseek(fd, 0, SEEK_SET);
    char buf[65536];
    for (ssize_t got; (got = ::read(fd, buf, sizeof buf)) > 0;) text.append(buf, static_cast<std::size_t>(got));
    std::fclose(file);
    return text;
}

}  // namespace

TEST_CASE("report rows: a file gets the text written into memory, on any thread count") {
    for (std::size_t n : {0, 1, 2, 50, 2000}) {
        for (int threads : {1, 2, 3}) {
            Table t;
            const RowWriter w = writer_of(t, n, 200000);  // about 20 rows a block
            int failed = -1;
            const std::string text = through_file(w, n, threads, &failed);
            CHECK_EQ(failed, 0);
            CHECK(text == in_memory(w, n));
        }
    }
    Table t;
    const RowWriter w = writer_of(t, 4, 1);
    CHECK(in_memory(w, 4).find("\"number\": null,") != std::string::npos);  // row 3's NaN
}

TEST_CASE("report rows: a write that fails stops the writer with its errno") {
    Table t;
    const RowWriter w = writer_of(t, 2000, 200000);
    int ends[2];
    REQUIRE(::pipe(ends) == 0);
    ::close(ends[0]);  // no reader: every write fails with EPIPE (SIGPIPE ignored here)
    std::signal(SIGPIPE, SIG_IGN);
    for (int threads : {1, 2, 4}) CHECK_EQ(w.write_to(ends[1], 2000, threads), EPIPE);
    ::close(ends[1]);
    const int full = ::open("/dev/full", O_WRONLY);
    if (full >= 0) {
        CHECK_EQ(w.write_to(full, 2000, 2), ENOSPC);
        CHECK_EQ(w.write_to(full, 0, 2), ENOSPC);
        ::close(full);
    }
}

TEST_CASE("report rows: a list of 3 numbers and a 4x4 matrix, each non-finite entry null") {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const std::vector<double> matrix = {1.0, 2.0, 3.0, 4.0, 0.5, nan, 0.0, -1.0,
                                        1e-5, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0};
    const std::vector<double> numbers = {1.0, nan, -0.0};
    std::vector<RowColumn> columns(2);
    columns[0].kind = RowColumn::kMatrix4, columns[0].key = "\"m\"", columns[0].reals = matrix.data();
    columns[1].kind = RowColumn::kNumbers3, columns[1].key = "\"v\"", columns[1].reals = numbers.data();
    const RowWriter w(std::move(columns), 1);
    // json.dumps({"x": [row]}, indent=2, sort_keys=True)'s list, NaN as None
    const std::string expected =
        "[\n    {\n      \"m\": [\n        [\n          1.0,\n          2.0,\n          3.0,\n"
        "          4.0\n        ],\n        [\n          0.5,\n          null,\n          0.0,\n"
        "          -1.0\n        ],\n        [\n          1e-05,\n          0.0,\n          1.0,\n"
        "          0.0\n        ],\n        [\n          0.0,\n          0.0,\n          0.0,\n"
        "          1.0\n        ]\n      ],\n      \"v\": [\n        1.0,\n        null,\n"
        "        -0.0\n      ]\n    }\n  ]";
    CHECK(in_memory(w, 1) == expected);
    int failed = -1;
    CHECK(through_file(w, 1, 2, &failed) == expected);
    CHECK_EQ(failed, 0);
}
