// Fast OBJ and STL readers and the vertex merge (see mesh_read.hpp).
//
// The parsers work on the raw bytes: no decoding, so a comment in any encoding is harmless and
// random bytes give "no faces" or a message with a line number, never a crash. Numbers are read
// with std::from_chars (locale-independent, exact round-trip).
#include "meshcol/mesh_read.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <new>
#include <string>
#include <string_view>
#include <utility>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "meshcol/batch.hpp"
#include "meshcol/defaults.hpp"

namespace meshcol {
namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// Splits a line (no newline in it) into whitespace-separated tokens.
void tokenize(std::string_view line, std::vector<std::string_view>& tokens) {
    tokens.clear();
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && is_space(line[i])) ++i;
        const size_t start = i;
        while (i < line.size() && !is_space(line[i])) ++i;
        if (i > start) tokens.push_back(line.substr(start, i - start));
    }
}

std::string_view trim(std::string_view s) {
    while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
    while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
    return s;
}

/// Parses a whole token as a double (an optional leading '+' allowed). False when the token is
/// not a number or overflows.
bool parse_double(std::string_view token, double& value) {
    if (!token.empty() && token.front() == '+') token.remove_prefix(1);
    const char* end = token.data() + token.size();
    const auto result = std::from_chars(token.data(), end, value);
    return result.ec == std::errc() && result.ptr == end;
}

/// Parses the leading integer of an OBJ face corner ("7", "7/2", "7//3", "-1/4/4").
bool parse_index(std::string_view token, long long& value) {
    const size_t slash = token.find('/');
    if (slash != std::string_view::npos) token = token.substr(0, slash);
    if (!token.empty() && token.front() == '+') token.remove_prefix(1);
    const char* end = token.data() + token.size();
    const auto result = std::from_chars(token.data(), end, value);
    return !token.empty() && result.ec == std::errc() && result.ptr == end;
}

std::string at_line(size_t line, const std::string& what) {
    return "line " + std::to_string(line) + ": " + what;
}

/// Calls `each(line_number, line)` for every logical line of `text` (a trailing backslash
/// joins the next line, as the OBJ specification allows); stops when `each` returns false.
template <class F>
void for_each_line(const char* data, size_t size, F&& each) {
    std::string joined;
    size_t line_number = 0;
    size_t first_line = 0;
    size_t i = 0;
    while (i < size) {
        const void* found = std::memchr(data + i, '\n', size - i);
        const size_t end = found ? static_cast<size_t>(static_cast<const char*>(found) - data) : size;
        std::string_view line(data + i, end - i);
        ++line_number;
        i = end + 1;
        std::string_view body = line;
        while (!body.empty() && (body.back() == '\r' || body.back() == ' ' || body.back() == '\t'))
            body.remove_suffix(1);
        if (!body.empty() && body.back() == '\\') {
            if (joined.empty()) first_line = line_number;
            joined.append(body.data(), body.size() - 1);
            joined.push_back(' ');
            continue;
        }
        if (!joined.empty()) {
            joined.append(line.data(), line.size());
            if (!each(first_line, std::string_view(joined))) return;
            joined.clear();
            continue;
        }
        if (!each(line_number, line)) return;
    }
    if (!joined.empty()) each(first_line, std::string_view(joined));
}

/// A face corner or vertex line read without tokenizing it whole: the common lines of a
/// well-formed file take this path; any line it does not read to the end goes to the exact
/// tokenizing path, which says what is wrong (the same messages as always).
class LineScanner {
  public:
    explicit LineScanner(std::string_view line) : line_(line) {}

    /// Skips separators; false at the end of the line or at a comment.
    bool more() {
        while (at_ < line_.size() && is_space(line_[at_])) ++at_;
        return at_ < line_.size() && line_[at_] != '#';
    }
    /// The key (first token), cut at a comment; call after more().
    std::string_view key() {
        const size_t start = at_;
        while (at_ < line_.size() && !is_space(line_[at_]) && line_[at_] != '#') ++at_;
        return line_.substr(start, at_ - start);
    }
    /// A whole token that is a number (one leading '+' allowed), finite; false for anything
    /// else (the exact path then says why).
    bool number(double& value) {
        if (!more()) return false;
        const char* begin = line_.data() + at_;
        const char* end = line_.data() + line_.size();
        if (*begin == '+') ++begin;
        const char* stop = plain_decimal(begin, end, value);
        if (stop == nullptr) {
            const auto result = std::from_chars(begin, end, value);
            if (result.ec != std::errc()) return false;
            stop = result.ptr;
        }
        if (!ends_token(stop) || !std::isfinite(value)) return false;
        at_ = static_cast<size_t>(stop - line_.data());
        return true;
    }
    /// A face corner ("7", "7/2", "7//3", "-1/4/4"): its leading integer, the rest of the
    /// token skipped; false when it is not one.
    bool corner(long long& value) {
        const char* begin = line_.data() + at_;
        const char* end = line_.data() + line_.size();
        if (*begin == '+') ++begin;
        const char* stop = plain_integer(begin, end, value);
        if (stop == nullptr) {
            const auto result = std::from_chars(begin, end, value);
            if (result.ec != std::errc() || result.ptr == begin) return false;
            stop = result.ptr;
        }
        if (stop < end && *stop == '/') {
            at_ = static_cast<size_t>(stop - line_.data());
            while (at_ < line_.size() && !is_space(line_[at_]) && line_[at_] != '#') ++at_;
            return true;
        }
        if (!ends_token(stop)) return false;
        at_ = static_cast<size_t>(stop - line_.data());
        return true;
    }

  private:
    /// An optional '-' and 1 to 18 digits (no overflow possible), read as std::from_chars
    /// reads them; where it ends, or nullptr for anything else (std::from_chars then).
    static const char* plain_integer(const char* p, const char* end, long long& value) {
        const bool negative = p < end && *p == '-';
        if (negative) ++p;
        const char* first = p;
        long long digits = 0;
        for (; p < end && static_cast<unsigned>(*p - '0') < 10 && p - first < 18; ++p)
            digits = digits * 10 + (*p - '0');
        if (p == first || (p < end && static_cast<unsigned>(*p - '0') < 10)) return nullptr;
        value = negative ? -digits : digits;
        return p;
    }
    /// A plain decimal (`-0.123456`: at most 15 digits, no exponent) read exactly: its digits
    /// as an integer, divided by a power of ten, both exact in a double, so the one rounding
    /// of the division gives the correctly rounded value, the bits std::from_chars gives
    /// (Clinger 1990). Where it ends, or nullptr for any other number (std::from_chars then).
    static const char* plain_decimal(const char* p, const char* end, double& value) {
        static constexpr double kPow10[] = {1e0, 1e1, 1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                            1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15};
        const bool negative = p < end && *p == '-';
        if (negative) ++p;
        std::uint64_t digits = 0;
        int count = 0, fraction = 0;
        for (; p < end && static_cast<unsigned>(*p - '0') < 10; ++p, ++count)
            digits = digits * 10 + static_cast<unsigned>(*p - '0');
        if (p < end && *p == '.')
            for (++p; p < end && static_cast<unsigned>(*p - '0') < 10; ++p, ++count, ++fraction)
                digits = digits * 10 + static_cast<unsigned>(*p - '0');
        if (count == 0 || count > 15 || (p < end && (*p == 'e' || *p == 'E'))) return nullptr;
        value = static_cast<double>(digits) / kPow10[fraction];
        if (negative) value = -value;
        return p;
    }
    bool ends_token(const char* p) const {
        return p == line_.data() + line_.size() || is_space(*p) || *p == '#';
    }
    std::string_view line_;
    size_t at_ = 0;
};

/// Copies the vertices `faces[begin, end)` (global indices into `vertices`) use into a new
/// object, in the order of their global index, and renumbers the faces locally. `remap` (one
/// entry per global vertex, all -1) is scratch space, returned all -1 again.
MeshObject gather(std::string name, const std::vector<double>& vertices,
                  const std::vector<std::int64_t>& faces, size_t begin, size_t end,
                  std::vector<std::int64_t>& remap, std::vector<std::int64_t>& ids) {
    MeshObject object;
    object.name = std::move(name);
    const size_t count = remap.size();
    ids.clear();
    for (size_t k = begin; k < end; ++k) {
        std::int64_t& slot = remap[static_cast<size_t>(faces[k])];
        if (slot < 0) {
            slot = 0;
            ids.push_back(faces[k]);
        }
    }
    if (ids.size() == count) {  // every vertex used (a file of one object): kept as it is
        for (const std::int64_t global : ids) remap[static_cast<size_t>(global)] = -1;
        object.vertices = vertices;
        object.faces.assign(faces.begin() + static_cast<std::ptrdiff_t>(begin),
                            faces.begin() + static_cast<std::ptrdiff_t>(end));
        return object;
    }
    std::sort(ids.begin(), ids.end());
    object.vertices.resize(3 * ids.size());
    for (size_t k = 0; k < ids.size(); ++k) {
        remap[static_cast<size_t>(ids[k])] = static_cast<std::int64_t>(k);
        std::memcpy(&object.vertices[3 * k], &vertices[3 * static_cast<size_t>(ids[k])],
                    3 * sizeof(double));
    }
    object.faces.resize(end - begin);
    for (size_t k = begin; k < end; ++k)
        object.faces[k - begin] = remap[static_cast<size_t>(faces[k])];
    for (const std::int64_t global : ids) remap[static_cast<size_t>(global)] = -1;
    return object;
}

/// Where an `o` line (or a `g` line) starts an object: at face `start` of the file.
struct ObjectStart {
    size_t start;
    std::string name;
    bool group;  ///< a `g` line: starts an object only in a file with no `o` line
};

/// The working arrays of `parse_obj`, kept from one file to the next by a reader thread (a
/// scene's 100,000 small files would otherwise grow and free a dozen vectors each).
struct ObjScratch {
    std::vector<double> vertices;
    std::vector<std::int64_t> faces;
    std::vector<ObjectStart> starts;
    std::vector<std::string_view> tokens;
    std::vector<long long> raw;
    std::vector<std::int64_t> corners, remap, ids;
};

/// A vertex's rounded coordinates: what `merge_vertices` compares.
struct Key {
    std::int64_t q[3];
    bool operator==(const Key& o) const {
        return q[0] == o.q[0] && q[1] == o.q[1] && q[2] == o.q[2];
    }
};

/// A slot of `merge_vertices`' table: a key's hash beside its merged index.
struct Slot {
    std::uint64_t hash;
    std::int64_t index;  // -1: empty
};

/// The working arrays of `merge_vertices`, kept the same way.
struct MergeScratch {
    std::vector<char> used;
    std::vector<std::int64_t> remap;
    std::vector<double> merged;
    std::vector<Slot> slots, recent;
    std::vector<Key> keys;
};

MeshFile parse_obj_with(const char* data, size_t size, ObjScratch& scratch);
void merge_with(std::vector<double>& vertices, std::vector<std::int64_t>& faces, int digits,
                MergeScratch& scratch);

}  // namespace

MeshFile parse_obj(const char* data, size_t size) {
    ObjScratch scratch;
    return parse_obj_with(data, size, scratch);
}

void merge_vertices(std::vector<double>& vertices, std::vector<std::int64_t>& faces, int digits) {
    MergeScratch scratch;
    merge_with(vertices, faces, digits, scratch);
}

namespace {

MeshFile parse_obj_with(const char* data, size_t size, ObjScratch& scratch) {
    MeshFile file;
    // One pass: vertices, faces (global, 0-based) and where each `o` and `g` line falls; at the
    // end, `g` lines split objects only when no line is an `o` line.
    bool has_object_lines = false;
    std::vector<double>& vertices = scratch.vertices;
    std::vector<std::int64_t>& faces = scratch.faces;
    std::vector<ObjectStart>& starts = scratch.starts;
    vertices.clear();
    faces.clear();
    starts.clear();
    long long largest = -1;      // the largest positive index seen, 0-based
    size_t largest_line = 0;
    std::vector<std::string_view>& tokens = scratch.tokens;
    std::vector<long long>& raw = scratch.raw;
    std::vector<std::int64_t>& corners = scratch.corners;

    // A face's corners, in order, as the file gives them: checked and triangulated.
    auto add_face = [&](size_t line_number, const std::vector<long long>& indices) {
        corners.clear();
        const long long defined = static_cast<long long>(vertices.size() / 3);
        for (long long index : indices) {
            if (index == 0) {
                file.error = at_line(line_number, "face index 0 (OBJ indices start at 1)");
                return false;
            }
            if (index < 0) {
                if (-index > defined) {
                    file.error = at_line(line_number,
                                         "relative face index " + std::to_string(index) +
                                             " but only " + std::to_string(defined) +
                                             " vertices precede it");
                    return false;
                }
                index = defined + index;
            } else {
                index -= 1;
                if (index > largest) {
                    largest = index;
                    largest_line = line_number;
                }
            }
            corners.push_back(index);
        }
        // A face of fewer than three vertices has no area: skipped, as trimesh does.
        for (size_t k = 1; k + 1 < corners.size(); ++k) {
            faces.push_back(corners[0]);
            faces.push_back(corners[k]);
            faces.push_back(corners[k + 1]);
        }
        return true;
    };

    // The exact path: the line tokenized whole, every fault named.
    auto exact_line = [&](size_t line_number, std::string_view line) {
        const size_t hash = line.find('#');
        if (hash != std::string_view::npos) line = line.substr(0, hash);
        tokenize(line, tokens);
        if (tokens.empty()) return true;
        const std::string_view key = tokens[0];
        if (key == "v") {
            double xyz[3];
            if (tokens.size() < 4) {
                file.error = at_line(line_number, "a vertex needs three coordinates");
                return false;
            }
            for (int k = 0; k < 3; ++k) {
                if (!parse_double(tokens[1 + k], xyz[k])) {
                    file.error = at_line(line_number, "vertex coordinate '" +
                                                          std::string(tokens[1 + k].substr(0, 40)) +
                                                          "' is not a number");
                    return false;
                }
                if (!std::isfinite(xyz[k])) {
                    file.error = at_line(line_number, "non-finite vertex coordinate");
                    return false;
                }
            }
            vertices.insert(vertices.end(), xyz, xyz + 3);
        } else if (key == "f") {
            raw.clear();
            const long long defined = static_cast<long long>(vertices.size() / 3);
            for (size_t k = 1; k < tokens.size(); ++k) {
                long long index = 0;
                if (!parse_index(tokens[k], index)) {
                    file.error = at_line(line_number, "face vertex '" +
                                                          std::string(tokens[k].substr(0, 40)) +
                                                          "' is not an index");
                    return false;
                }
                if (index == 0) {
                    file.error = at_line(line_number, "face index 0 (OBJ indices start at 1)");
                    return false;
                }
                if (index < 0 && -index > defined) {
                    file.error = at_line(line_number, "relative face index " +
                                                          std::to_string(index) + " but only " +
                                                          std::to_string(defined) +
                                                          " vertices precede it");
                    return false;
                }
                raw.push_back(index);
            }
            return add_face(line_number, raw);
        } else if (key == "o" || key == "g") {
            std::string_view name = trim(line);
            name.remove_prefix(1);
            starts.push_back(ObjectStart{faces.size() / 3, std::string(trim(name)), key == "g"});
        }
        return true;
    };

    for_each_line(data, size, [&](size_t line_number, std::string_view line) {
        LineScanner scan(line);
        if (!scan.more()) return true;  // blank, or a comment
        const std::string_view key = scan.key();
        if (key.data()[0] == 'o') {  // an `o` line as the file has it, comment and all
            const size_t after = static_cast<size_t>(key.data() - line.data()) + 1;
            has_object_lines |= after == line.size() || is_space(line[after]);
        }
        if (key == "v") {
            double xyz[3];
            if (scan.number(xyz[0]) && scan.number(xyz[1]) && scan.number(xyz[2])) {
                vertices.insert(vertices.end(), xyz, xyz + 3);
                return true;
            }
        } else if (key == "f") {
            raw.clear();
            long long index = 0;
            bool whole = true;
            while (scan.more()) {
                if (!scan.corner(index)) {
                    whole = false;
                    break;
                }
                raw.push_back(index);
            }
            if (whole) return add_face(line_number, raw);
        } else if (key != "o" && key != "g") {
            return true;  // vt, vn, usemtl, s, ...: skipped
        }
        return exact_line(line_number, line);
    });
    if (!file.error.empty()) return file;
    const long long count = static_cast<long long>(vertices.size() / 3);
    if (largest >= count) {
        file.error = at_line(largest_line, "face index " + std::to_string(largest + 1) +
                                               " but the file has " + std::to_string(count) +
                                               (count == 1 ? " vertex" : " vertices"));
        return file;
    }
    std::vector<std::int64_t>& remap = scratch.remap;
    remap.assign(static_cast<size_t>(count), -1);
    // the objects: from the first face, then from each `o` line (and `g` line, without `o`)
    std::string first_name;
    size_t begin = 0;
    std::string* name = &first_name;
    auto close = [&](size_t end) {
        if (end > begin)
            file.objects.push_back(
                gather(std::move(*name), vertices, faces, 3 * begin, 3 * end, remap, scratch.ids));
    };
    for (ObjectStart& at : starts) {
        if (at.group && has_object_lines) continue;
        close(at.start);
        begin = at.start;
        name = &at.name;
    }
    close(faces.size() / 3);
    return file;
}

}  // namespace

MeshFile parse_stl(const char* data, size_t size) {
    MeshFile file;
    if (size >= 84) {
        std::uint32_t count = 0;
        std::memcpy(&count, data + 80, 4);  // little-endian, as every supported platform
        if (84 + 50 * static_cast<std::uint64_t>(count) == size) {
            MeshObject object;
            object.vertices.resize(9 * static_cast<size_t>(count));
            object.faces.resize(3 * static_cast<size_t>(count));
            for (std::uint32_t t = 0; t < count; ++t) {
                float corner[9];
                std::memcpy(corner, data + 84 + 50 * static_cast<size_t>(t) + 12, sizeof corner);
                for (int k = 0; k < 9; ++k) {
                    if (!std::isfinite(corner[k])) {
                        file.error = "triangle " + std::to_string(t) +
                                     " has a non-finite vertex coordinate";
                        return file;
                    }
                    object.vertices[9 * static_cast<size_t>(t) + k] = corner[k];
                }
                for (int k = 0; k < 3; ++k)
                    object.faces[3 * static_cast<size_t>(t) + k] = 3 * static_cast<std::int64_t>(t) + k;
            }
            if (count > 0) file.objects.push_back(std::move(object));
            return file;
        }
    }
    // ASCII: solid name / facet normal ... / outer loop / vertex x y z (x3) / endloop /
    // endfacet / endsolid.
    if (size > 0 && std::memchr(data, '\0', size) != nullptr) {  // data: null when empty
        file.error =
            "neither binary STL (size does not match the triangle count) nor ASCII text";
        return file;
    }
    size_t start = 0;
    while (start < size && (is_space(data[start]) || data[start] == '\n')) ++start;
    if (size - start < 5 || std::memcmp(data + start, "solid", 5) != 0) {
        file.error =
            "neither binary STL (size does not match the triangle count) nor ASCII STL "
            "(no 'solid' line)";
        return file;
    }
    std::vector<std::string_view> tokens;
    MeshObject* object = nullptr;
    int loop_corners = 0;
    size_t loop_line = 0;  // the line of the `outer loop` still open (0: none)
    for_each_line(data, size, [&](size_t line_number, std::string_view line) {
        tokenize(line, tokens);
        if (tokens.empty()) return true;
        const std::string_view key = tokens[0];
        if (key == "solid") {
            loop_line = 0;
            std::string_view name = trim(line);
            name.remove_prefix(5);
            file.objects.push_back(MeshObject{std::string(trim(name)), {}, {}});
            object = &file.objects.back();
            // A loop left open by the previous solid ends here: its corners stay behind with
            // that solid (unused), so an `endloop` in this one never counts them as its own
            // (its face would index before this solid's first vertex).
            loop_corners = 0;
        } else if (key == "vertex") {
            if (object == nullptr) {
                file.error = at_line(line_number, "vertex outside a solid");
                return false;
            }
            if (tokens.size() < 4) {
                file.error = at_line(line_number, "a vertex needs three coordinates");
                return false;
            }
            for (int k = 0; k < 3; ++k) {
                double value = 0.0;
                if (!parse_double(tokens[1 + k], value)) {
                    file.error = at_line(line_number, "vertex coordinate '" +
                                                          std::string(tokens[1 + k].substr(0, 40)) +
                                                          "' is not a number");
                    return false;
                }
                if (!std::isfinite(value)) {
                    file.error = at_line(line_number, "non-finite vertex coordinate");
                    return false;
                }
                object->vertices.push_back(value);
            }
            ++loop_corners;
        } else if (key == "endloop") {
            if (loop_corners != 3) {
                file.error = at_line(line_number, "a facet has " + std::to_string(loop_corners) +
                                                      " vertices, not 3");
                return false;
            }
            const std::int64_t first = static_cast<std::int64_t>(object->vertices.size() / 3) - 3;
            for (int k = 0; k < 3; ++k) object->faces.push_back(first + k);
            loop_corners = 0;
            loop_line = 0;
        } else if (key == "outer") {
            loop_corners = 0;
            loop_line = line_number;
        }
        return true;
    });
    if (!file.error.empty()) return file;
    // A file cut short inside a facet (a copy or download that stopped) is not a whole mesh:
    // its last triangle would be dropped silently.
    if (loop_line != 0 || loop_corners != 0)
        file.error = at_line(loop_line, "the file ends inside this facet's loop (cut short?)");
    if (!file.error.empty()) return file;
    std::vector<MeshObject> kept;
    for (auto& o : file.objects)
        if (!o.faces.empty()) kept.push_back(std::move(o));
    file.objects = std::move(kept);
    return file;
}

namespace {

void merge_with(std::vector<double>& vertices, std::vector<std::int64_t>& faces, int digits,
                MergeScratch& scratch) {
    const size_t n = vertices.size() / 3;
    std::vector<char>& used = scratch.used;
    used.assign(n, 0);
    for (const std::int64_t f : faces) used[static_cast<size_t>(f)] = 1;

    struct KeyHash {
        std::uint64_t operator()(const Key& k) const {
            std::uint64_t h = 0;
            for (std::int64_t v : k.q) {  // splitmix64 of each coordinate, chained
                std::uint64_t z = static_cast<std::uint64_t>(v) + h + 0x9e3779b97f4a7c15ull;
                z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
                z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
                h = z ^ (z >> 31);
            }
            return h;
        }
    };
    const double scale = std::pow(10.0, digits);
    // |q| below 2^62 converts exactly; a larger coordinate keys on its own bits (tagged so it
    // never equals a rounded key), so it only merges with an equal coordinate.
    const double limit = 4.6e18;
    auto quantise = [&](double x) -> std::int64_t {
        const double r = std::nearbyint(x * scale - 1e-6);
        // Times 2, not a shift: shifting a negative value left is undefined before C++20.
        if (std::fabs(r) < limit) return static_cast<std::int64_t>(r) * 2;
        std::int64_t bits;
        std::memcpy(&bits, &x, sizeof bits);
        return bits | 1;
    };

    // Open addressing with linear probing, kept at most half full and grown as merged vertices
    // are found (a triangle soup has ~6x fewer than its corners). A slot holds the key's hash
    // beside the merged index, so a probe reads the key itself only on a hash match.
    // Sized to the object: a scene's props are small, and tables of a fixed 80 KiB each
    // cost more to clear than to fill (results never depend on the sizes).
    // A large soup (a 2-million-triangle STL) starts near its final size, half full at the
    // expected one merged vertex per six corners, instead of growing through a dozen rehashes.
    size_t capacity = 16;
    const size_t expected = n >= 65536 ? n / 3 : 0;
    while (capacity < 2 * n && (capacity < 1024 || capacity < expected)) capacity <<= 1;
    std::vector<Slot>& slots = scratch.slots;
    slots.assign(capacity, Slot{0, -1});
    std::vector<Key>& keys = scratch.keys;
    keys.clear();
    const KeyHash hasher;
    auto insert_slot = [&](std::uint64_t h, std::int64_t index) {
        size_t at = h & (capacity - 1);
        while (slots[at].index >= 0) at = (at + 1) & (capacity - 1);
        slots[at] = Slot{h, index};
    };
    std::vector<std::int64_t>& remap = scratch.remap;
    remap.assign(n, -1);
    std::vector<double>& merged = scratch.merged;
    merged.clear();
    // A small object's merged vertices fit in what its corners take (no regrowth); a large
    // soup's are about a sixth of its corners.
    const size_t reserve = n < 65536 ? n : n / 4;
    keys.reserve(reserve);
    merged.reserve(3 * reserve);
    size_t recent_size = 16;  // at most 4096 slots (64 KiB), a power of two
    while (recent_size < n && recent_size < 4096) recent_size <<= 1;
    const size_t kRecent = recent_size;
    std::vector<Slot>& recent = scratch.recent;
    recent.assign(kRecent, Slot{0, -1});
    // Corners go in blocks: each block's keys and hashes first, with their table slots
    // prefetched, then looked up one by one in order (the same lookups as one at a time, so
    // the same numbering). A big soup's lookups are cache misses in a table of tens of MiB;
    // prefetched, a block's misses overlap instead of queueing.
    constexpr size_t kBlock = 16;
    size_t block_corner[kBlock];
    Key block_key[kBlock];
    std::uint64_t block_hash[kBlock];
    for (size_t next = 0; next < n;) {
        size_t count = 0;
        for (; next < n && count < kBlock; ++next) {
            if (!used[next]) continue;
            const double* v = &vertices[3 * next];
            block_corner[count] = next;
            block_key[count] = Key{{quantise(v[0]), quantise(v[1]), quantise(v[2])}};
            block_hash[count] = hasher(block_key[count]);
            __builtin_prefetch(&slots[block_hash[count] & (capacity - 1)]);
            ++count;
        }
        for (size_t b = 0; b < count; ++b) {
            const size_t i = block_corner[b];
            const Key& key = block_key[b];
            const std::uint64_t h = block_hash[b];
            // Neighbouring triangles share corners: a small direct-mapped table of the keys
            // seen last answers most repeats from cache.
            Slot& seen = recent[h & (kRecent - 1)];
            if (seen.index >= 0 && seen.hash == h && keys[static_cast<size_t>(seen.index)] == key) {
                remap[i] = seen.index;
                continue;
            }
            size_t at = h & (capacity - 1);
            std::int64_t found = -1;
            while (slots[at].index >= 0) {
                if (slots[at].hash == h && keys[static_cast<size_t>(slots[at].index)] == key) {
                    found = slots[at].index;
                    break;
                }
                at = (at + 1) & (capacity - 1);
            }
            if (found < 0) {
                found = static_cast<std::int64_t>(keys.size());
                keys.push_back(key);
                const double* v = &vertices[3 * i];
                merged.insert(merged.end(), v, v + 3);
                slots[at] = Slot{h, found};
                if (2 * keys.size() > capacity) {  // grow: rehash every key
                    capacity <<= 1;
                    slots.assign(capacity, Slot{0, -1});
                    for (size_t k = 0; k < keys.size(); ++k)
                        insert_slot(hasher(keys[k]), static_cast<std::int64_t>(k));
                }
            }
            remap[i] = found;
            seen = Slot{h, found};
        }
    }
    for (std::int64_t& f : faces) f = remap[static_cast<size_t>(f)];
    vertices.assign(merged.begin(), merged.end());  // within its room: no new allocation
}

/// What a file that is not regular is, for the message (as meshcol/io/safe_read.py says it).
const char* special_kind(mode_t mode) {
    if (S_ISFIFO(mode)) return "a named pipe";
    if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
    if (S_ISSOCK(mode)) return "a socket";
    return "not a regular file";
}

/// A path's folder kept open from one path to the next, so that opening or stat'ing a file
/// relative to it walks one name instead of the whole path (100,000 files in one folder).
/// The same file, the same errors: the folder is opened by the same path (symbolic links
/// followed as the walk would) with O_PATH, which needs no read permission, and any failure to
/// open it, or a path without a folder and a name, falls back to the whole path.
class FolderCursor {
  public:
    FolderCursor() = default;
    FolderCursor(const FolderCursor&) = delete;
    FolderCursor& operator=(const FolderCursor&) = delete;
    ~FolderCursor() {
        if (fd_ >= 0) ::close(fd_);
    }

    /// Where `path` is reached from: (the folder's descriptor, the last name) or (AT_FDCWD,
    /// the whole path), for the *at system calls.
    std::pair<int, const char*> locate(const std::string& path) {
#ifdef O_PATH
        const size_t slash = path.rfind('/');
        if (slash != std::string::npos && slash > 0 && slash + 1 < path.size()) {
            const std::string_view folder(path.data(), slash);
            if (fd_ < 0 || folder != folder_) {
                if (fd_ >= 0) ::close(fd_);
                folder_.assign(folder);
                fd_ = ::open(folder_.c_str(), O_PATH | O_DIRECTORY | O_CLOEXEC);
            }
            if (fd_ >= 0) return {fd_, path.c_str() + slash + 1};
        }
#endif
        return {AT_FDCWD, path.c_str()};
    }

  private:
    std::string folder_;  // the folder `fd_` is open on ("" with -1: none)
    int fd_ = -1;
};

/// What a reader thread keeps from one file to the next: the file's bytes, the parser's and
/// the merge's working arrays, and the folder of the last file.
struct ReadScratch {
    std::vector<char> buffer;
    ObjScratch obj;
    MergeScratch merge;
    FolderCursor folder;
};

/// Opens `path` as `open` would, relative to its folder when the last file was in the same
/// folder (`FolderCursor`).
int open_in_folder(const std::string& path, int flags, ReadScratch& scratch) {
    const auto [folder, name] = scratch.folder.locate(path);
    return ::openat(folder, name, flags);
}

void read_one(const std::string& path, MeshFormat format, bool merge, ReadScratch& scratch,
              MeshFile& out) {
    std::vector<char>& buffer = scratch.buffer;
    // Opened without blocking (a named pipe would wait for a writer forever) and checked on the
    // open descriptor before a byte is read: only a regular file within the cap is read.
    // Plain descriptors, no stdio: a scene may name 100,000 small files.
    const int fd = open_in_folder(path, O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC, scratch);
    if (fd < 0) {
        const int code = errno;
        out.status = code == ENOENT ? ReadStatus::NotFound : ReadStatus::Unreadable;
        out.error = code == ENOENT ? "file not found"
                                   : std::string("cannot read file: ") + std::strerror(code);
        return;
    }
    struct Closer {  // closed on every way out, a std::bad_alloc of the buffer included
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    struct stat info {};
    if (fstat(fd, &info) != 0 || S_ISDIR(info.st_mode)) {
        out.status = ReadStatus::Directory;
        out.error = "is a directory, not a mesh file";
        return;
    }
    if (!S_ISREG(info.st_mode)) {
        out.status = ReadStatus::Unreadable;
        out.error = std::string("is ") + special_kind(info.st_mode) + ", not a regular file";
        return;
    }
    const std::uint64_t cap = static_cast<std::uint64_t>(defaults::max_mesh_file_bytes);
    if (static_cast<std::uint64_t>(info.st_size) > cap) {
        out.status = ReadStatus::Unreadable;
        out.error = "mesh file is " + std::to_string(info.st_size) + " bytes, over the limit of " +
                    std::to_string(cap) + " bytes";
        return;
    }
    // The whole file straight into the buffer, then whatever a growing file adds (to the cap).
    if (buffer.size() < static_cast<size_t>(info.st_size) + (1 << 12))
        buffer.resize(static_cast<size_t>(info.st_size) + (1 << 12));
    size_t size = 0;
    int code = 0;
    for (;;) {
        if (size == buffer.size()) {
            if (size > cap) {
                out.status = ReadStatus::Unreadable;
                out.error = "mesh file grew over the limit of " + std::to_string(cap) + " bytes";
                return;
            }
            buffer.resize(std::min<size_t>(2 * size, static_cast<size_t>(cap) + 1));
        }
        const ssize_t got = ::read(fd, buffer.data() + size, buffer.size() - size);
        if (got > 0) {
            size += static_cast<size_t>(got);
            // a short read that ends where fstat said the file ends: the whole file, with no
            // second read to hear the end (a file growing meanwhile reads on to its end)
            if (size == static_cast<size_t>(info.st_size) && size < buffer.size()) break;
            continue;
        }
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) code = errno;
        break;
    }
    if (size > cap) {
        out.status = ReadStatus::Unreadable;
        out.error = "mesh file grew over the limit of " + std::to_string(cap) + " bytes";
        return;
    }
    if (code != 0) {
        out.status = code == EISDIR ? ReadStatus::Directory : ReadStatus::Unreadable;
        out.error = code == EISDIR ? "is a directory, not a mesh file"
                                   : std::string("cannot read file: ") + std::strerror(code);
        return;
    }
    // the buffer keeps its size for the next file (never shrunk, so never filled again)
    out = format == MeshFormat::Obj ? parse_obj_with(buffer.data(), size, scratch.obj)
                                    : parse_stl(buffer.data(), size);
    if (!out.error.empty()) {
        out.status = ReadStatus::Corrupt;
        out.objects.clear();  // a file that does not parse gives a message instead of objects
    }
    if (merge && out.error.empty())
        for (MeshObject& object : out.objects)
            merge_with(object.vertices, object.faces, 8, scratch.merge);
}

}  // namespace

std::vector<MeshFile> read_mesh_files(const std::vector<std::string>& paths,
                                      const std::vector<MeshFormat>& formats, bool merge,
                                      int threads) {
    std::vector<MeshFile> files(paths.size());
    const long long n = static_cast<long long>(paths.size());
    parallel_for(n, resolve_threads(threads, n, 4), [&](long long begin, long long end) {
        ReadScratch scratch;
        for (long long i = begin; i < end; ++i) {
            MeshFile& out = files[static_cast<size_t>(i)];
            try {
                read_one(paths[static_cast<size_t>(i)], formats[static_cast<size_t>(i)], merge,
                         scratch, out);
            } catch (const std::bad_alloc&) {
                out = MeshFile{};
                out.status = ReadStatus::Unreadable;
                out.error = "file too large to read into memory";
            }
        }
    });
    return files;
}

std::vector<PackedStart> packed_starts(const std::vector<MeshFile>& files) {
    std::vector<PackedStart> starts(files.size() + 1);
    PackedStart at;
    for (size_t i = 0; i < files.size(); ++i) {
        starts[i] = at;
        for (const MeshObject& o : files[i].objects) {
            at.object += 1;
            at.vertex += static_cast<std::int64_t>(o.vertices.size() / 3);
            at.face += static_cast<std::int64_t>(o.faces.size() / 3);
        }
    }
    starts[files.size()] = at;
    return starts;
}

// A packed face index is an int32: an object's vertices number fewer than 2^31, since each
// takes at least 8 bytes of its file (an OBJ "v 0 0 0" line; an STL corner, 12 bytes of a
// 50-byte binary facet or a longer "vertex" line) and no file is over the cap.
static_assert(defaults::max_mesh_file_bytes / 8 <= std::numeric_limits<std::int32_t>::max(),
              "a face index of a file within the cap fits an int32");

void pack_mesh_files(std::vector<MeshFile>& files, const std::vector<PackedStart>& starts,
                     int threads, double* vertices, std::int32_t* faces,
                     std::int64_t* vertex_offsets, std::int64_t* face_offsets,
                     std::int64_t* object_file, double* largest) {
    const long long n = static_cast<long long>(files.size());
    vertex_offsets[starts[files.size()].object] = starts[files.size()].vertex;
    face_offsets[starts[files.size()].object] = starts[files.size()].face;
    parallel_for(n, resolve_threads(threads, n, 256), [&](long long begin, long long end) {
        for (long long i = begin; i < end; ++i) {
            PackedStart at = starts[static_cast<size_t>(i)];
            for (MeshObject& o : files[static_cast<size_t>(i)].objects) {
                const size_t k = static_cast<size_t>(at.object);
                vertex_offsets[k] = at.vertex;
                face_offsets[k] = at.face;
                object_file[k] = i;
                double top = 0.0;
                for (const double v : o.vertices) {
                    const double a = std::fabs(v);
                    top = a > top || a != a ? a : top;  // NaN sticks: never "within a limit"
                    if (top != top) break;
                }
                largest[k] = top;
                // whole rows only, as packed_starts counted them
                const size_t v_rows = o.vertices.size() / 3, f_rows = o.faces.size() / 3;
                if (v_rows != 0)
                    std::memcpy(vertices + 3 * at.vertex, o.vertices.data(),
                                3 * v_rows * sizeof(double));
                std::int32_t* to = faces + 3 * at.face;
                for (size_t e = 0; e < 3 * f_rows; ++e)
                    to[e] = static_cast<std::int32_t>(o.faces[e]);
                at.object += 1;
                at.vertex += static_cast<std::int64_t>(o.vertices.size() / 3);
                at.face += static_cast<std::int64_t>(o.faces.size() / 3);
                std::vector<double>().swap(o.vertices);
                std::vector<std::int64_t>().swap(o.faces);
            }
        }
    });
}

void file_identities(const std::vector<std::string>& paths, int threads, std::uint64_t* device,
                     std::uint64_t* inode, std::uint8_t* found) {
    const long long n = static_cast<long long>(paths.size());
    parallel_for(n, resolve_threads(threads, n, 256), [&](long long begin, long long end) {
        FolderCursor cursor;  // stat as `stat` would, relative to the folder of the last path
        for (long long i = begin; i < end; ++i) {
            struct stat info {};
            const auto [folder, name] = cursor.locate(paths[static_cast<size_t>(i)]);
            const bool ok = ::fstatat(folder, name, &info, 0) == 0;
            device[i] = ok ? static_cast<std::uint64_t>(info.st_dev) : 0;
            inode[i] = ok ? static_cast<std::uint64_t>(info.st_ino) : 0;
            found[i] = ok ? 1 : 0;
        }
    });
}

}  // namespace meshcol
