#pragma once
// The result of a batched query as one numpy array per field of its output struct. A query
// kind lists its fields once (name, member, array element type); `Columns` allocates the
// arrays, writes item k from an output struct (any thread, distinct k) and hands them to
// Python as a dict by name, which the Python result dataclass takes as keywords (a missing or
// extra name fails there at once). `run_items` is the loop of every such batch: GIL released,
// items on threads, one output struct each.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cstddef>
#include <cstdint>
#include <tuple>
#include <type_traits>
#include <utility>

#include "meshcol/batch.hpp"
#include "meshcol/vec.hpp"
#include "ndarray.hpp"

namespace meshcol::bindings {

namespace nb = nanobind;

/// One field of `Output` as a column: its Python name, the member, and the element type of
/// its array (`Vec3` gives an (N, 3) float64 array, any other type an (N,) array of it).
template <class Output, class Member, class Element>
struct Field {
    const char* name;
    Member Output::*member;
};

/// A column with the member's own type (double, bool, std::int64_t, Vec3).
template <class Output, class Member>
constexpr Field<Output, Member, Member> field(const char* name, Member Output::*member) {
    return {name, member};
}

/// A column stored as `Element` (an enum or an int member as std::int8_t, say).
template <class Element, class Output, class Member>
constexpr Field<Output, Member, Element> field_as(const char* name, Member Output::*member) {
    return {name, member};
}

namespace detail {

template <class Element>
struct ColumnArray {
    using type = Out<Element, -1>;
    static type make(size_t n) { return new_array<type>({n}); }
    template <class Member>
    static void write(type& a, long long k, const Member& value) {
        a.data()[k] = static_cast<Element>(value);
    }
};

template <>
struct ColumnArray<Vec3> {
    using type = Out<double, -1, 3>;
    static type make(size_t n) { return new_array<type>({n, 3}); }
    static void write(type& a, long long k, const Vec3& value) { store_row(a.data(), k, value); }
};

}  // namespace detail

/// The arrays of a batch of `n` items of `Output`, one per field of `fields`.
template <class Output, class... Fields>
class Columns {
public:
    Columns(size_t n, const std::tuple<Fields...>& fields)
        : fields_(fields), arrays_(make(n, std::index_sequence_for<Fields...>{})) {}

    /// Writes item k's fields (threads may write distinct items at once).
    void write(long long k, const Output& item) {
        write_each(k, item, std::index_sequence_for<Fields...>{});
    }

    /// {name: array} for the Python result class.
    nb::dict dict() {
        nb::dict out;
        add_each(out, std::index_sequence_for<Fields...>{});
        return out;
    }

private:
    template <class F>
    struct Of;
    template <class M, class E>
    struct Of<Field<Output, M, E>> {
        using array = detail::ColumnArray<E>;
    };
    using Arrays = std::tuple<typename Of<Fields>::array::type...>;

    template <size_t... I>
    Arrays make(size_t n, std::index_sequence<I...>) {
        return Arrays(Of<Fields>::array::make(n)...);
    }
    template <size_t... I>
    void write_each(long long k, const Output& item, std::index_sequence<I...>) {
        (Of<std::tuple_element_t<I, std::tuple<Fields...>>>::array::write(
             std::get<I>(arrays_), k, item.*(std::get<I>(fields_).member)),
         ...);
    }
    template <size_t... I>
    void add_each(nb::dict& out, std::index_sequence<I...>) {
        ((out[std::get<I>(fields_).name] = std::get<I>(arrays_).cast()), ...);
    }

    std::tuple<Fields...> fields_;
    Arrays arrays_;
};

/// The columns of `fields` for n items.
template <class Output, class... Fields>
Columns<Output, Fields...> columns_of(size_t n, const std::tuple<Fields...>& fields) {
    return Columns<Output, Fields...>(n, fields);
}

/// Runs `item(k)` (an `Output`) for k in [0, n) on threads with the GIL released, written
/// to `columns`; `min_per_thread` items at least per thread (defaults.hpp).
template <class Output, class Item, class... Fields>
void run_items(long long n, int threads, long long min_per_thread, Columns<Output, Fields...>& columns,
               Item item) {
    nb::gil_scoped_release release;
    parallel_for(n, resolve_threads(threads, n, min_per_thread), [&](long long begin, long long end) {
        for (long long k = begin; k < end; ++k) columns.write(k, item(k));
    });
}

}  // namespace meshcol::bindings
