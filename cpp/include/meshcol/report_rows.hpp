#pragma once
/// The report writer's rows (issue 32 items 4-5): a list of JSON objects of one set of keys,
/// each value from a column, as Python's json.dumps(rows, sort_keys=True, indent=2) writes it
/// nested at some level, floats as repr(float) (format.hpp) and non-finite numbers as null.
/// Written into memory, or straight into a file descriptor in blocks formatted on several
/// threads. The bindings (bind_report.cpp) take the columns from numpy arrays and escape the
/// keys and string tables; nothing here knows Python.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace meshcol {

/// One column of rows: its key (JSON-escaped, quotes included) and where a row's value is.
struct RowColumn {
    enum Kind { kNumber, kVector, kBox, kNumbers3, kMatrix4, kInteger, kIndex, kBoolean, kString, kRaw } kind =
        kNumber;
    std::string key;
    /// kNumber (n), kVector and kNumbers3 (n x 3), kBox (n x 6), kMatrix4 (n x 16, row-major)
    const double* reals = nullptr;
    const std::int64_t* integers = nullptr;  ///< kInteger, kIndex, and the codes of kString, kRaw
    const bool* flags = nullptr;             ///< kBoolean
    /// kString: escaped entries; kRaw: JSON text (shared: the columns of body_a and body_b
    /// are one table of a million names)
    std::shared_ptr<const std::vector<std::string>> table;
};

/// Rows of `columns` (in key order) as a list's items at nesting `level`: row i is ',' (but
/// for i = 0), a newline, the object; a number column's non-finite value and a vector or box
/// with one is null, a negative index or code is null. kNumbers3 is a list of 3 numbers and
/// kMatrix4 a list of 4 lists of 4 (a 4x4 pose), each non-finite entry null on its own (as
/// json writes a list of floats).
class RowWriter {
public:
    RowWriter(std::vector<RowColumn> columns, int level);

    /// The most chars one row takes (its ',' and newlines included).
    std::size_t row_bound() const { return row_bound_; }

    /// Rows from..to at `out` (room for (to - from) * row_bound() chars); returns the end.
    char* write(std::size_t from, std::size_t to, char* out) const;

    /// The whole list's text into `fd` at its offset: '[', rows 0..count, a newline and ']'
    /// ('[]' when count is 0). Blocks of rows are formatted on `threads` threads (0: all
    /// cores) into a ring of buffers made once and written in order as they are done, a few
    /// megabytes a write. Returns 0, or the errno of the write that failed (the rows after
    /// it are not written; the file holds part of the list).
    int write_to(int fd, std::size_t count, int threads) const;

private:
    std::vector<RowColumn> columns_;
    std::vector<std::string> prefixes_;  ///< ",\n<indent>key: " (the first column without ',')
    int level_;
    std::size_t row_bound_ = 0;
};

/// Writes all of `data` to `fd` (partial writes continued, EINTR retried): 0 or the errno.
int write_all(int fd, const char* data, std::size_t size);

}  // namespace meshcol
