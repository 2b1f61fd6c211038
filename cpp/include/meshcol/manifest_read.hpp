#pragma once
/// A JSON scene manifest of static mesh and primitive bodies read straight into columns,
/// without a Python object per body but its name and mesh: the fast path of
/// `meshcol.io.scene_native`.
///
/// It reads one shape of document only, the common one: a top object of `units`, `duration`
/// and a non-empty `bodies` array, each body an object of `name`, exactly one of `mesh` (a
/// file name) or `primitive` (a known type with exactly its fields, positive numbers), and
/// optionally `position`, `rotation` (a quaternion, or Euler angles and an order) and `shape`;
/// numbers finite, names and mesh names non-empty UTF-8 without escapes, no key twice. Anything else (another field, an escape, a syntax
/// error, a NaN, a number out of range, a duplicate key...) gives `plain == false` and the
/// Python reader decides, with its messages: this reader never rejects, it only passes over.
/// What it passes is what Python's json module and `meshcol.io.scene_columns.columns` make
/// of the same bytes, to the bit (tests/test_scene_native.py, fuzz target `manifest`).

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace meshcol {

/// The manifest's words, from its schema (Python passes them): the primitive types and the
/// fields each has besides `type` (bits: 1 radius, 2 length, 4 size, 8 semi_axes), the Euler
/// orders and the collider shapes. A body's codes index these lists.
struct ManifestWords {
    std::vector<std::string> types;
    std::vector<int> type_fields;
    std::vector<std::string> orders;
    std::vector<std::string> shapes;
};

/// Bits of `ManifestWords::type_fields`.
enum PrimitiveField : int { kRadius = 1, kLength = 2, kSize = 4, kSemiAxes = 8 };

/// The columns of a plain manifest (n bodies), index-aligned.
struct ManifestColumns {
    bool plain = false;                  ///< false: not of the common shape (nothing else set)
    bool has_units = false, has_duration = false;
    std::string_view units;              ///< UTF-8, non-empty, a view into the text
    std::string_view duration;           ///< the number as written (Python reads its type)
    std::vector<std::string_view> names; ///< UTF-8, non-empty, views into the text
    std::vector<std::string_view> meshes; ///< UTF-8 views into the text, empty: a primitive body
    std::size_t mesh_count = 0;          ///< mesh bodies
    std::vector<std::int8_t> kinds;      ///< index into `types`, -1 for a mesh body
    std::vector<double> lengths;         ///< 3 a body: size, (radius, 0, 0), (radius, length, 0),
                                         ///< semi_axes; zeros for a mesh body
    std::vector<double> positions;       ///< 3 a body, zeros where absent
    std::size_t position_count = 0;      ///< bodies that give a position
    std::vector<std::int8_t> rotation;   ///< 0 none, 1 quaternion, 2 Euler angles
    std::vector<double> quaternions;     ///< 4 a quaternion body, in order
    std::vector<double> euler;           ///< 3 an Euler body, in order
    std::vector<std::int8_t> orders;     ///< an Euler body's order, index into `orders`
    std::vector<std::int8_t> shapes;     ///< index into `shapes`, -1 where absent
};

/// Reads `text` (the manifest's bytes; a leading UTF-8 byte-order mark is skipped) when it
/// is a plain manifest; else `plain == false`. The views point into `text`, which must
/// outlive the result.
ManifestColumns read_plain_manifest(std::string_view text, const ManifestWords& words);

/// A token of the JSON number grammar (checked by the caller) as Python's json module and
/// float() make it a double: the correctly rounded value, +0.0 for an integer zero ("-0" is
/// the integer 0). False for a token over 64 bytes or a value out of a double's range.
bool json_number(std::string_view token, double& value);

}  // namespace meshcol
