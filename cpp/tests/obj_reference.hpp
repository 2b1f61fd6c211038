// The OBJ parser as it was before the one-pass reader (main cfb6a83, cpp/src/mesh_read.cpp),
// kept verbatim as the reference the new parser must match byte for byte: objects, names,
// vertices to the bit, faces and every error message (test_mesh_read.cpp).
#pragma once

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "meshcol/mesh_read.hpp"

namespace reference {
using meshcol::MeshFile;
using meshcol::MeshObject;


inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// Splits a line (no newline in it) into whitespace-separated tokens.
inline void tokenize(std::string_view line, std::vector<std::string_view>& tokens) {
    tokens.clear();
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && is_space(line[i])) ++i;
        const size_t start = i;
        while (i < line.size() && !is_space(line[i])) ++i;
        if (i > start) tokens.push_back(line.substr(start, i - start));
    }
}

inline std::string_view trim(std::string_view s) {
    while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
    while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
    return s;
}

/// Parses a whole token as a double (an optional leading '+' allowed). False when the token is
/// not a number or overflows.
inline bool parse_double(std::string_view token, double& value) {
    if (!token.empty() && token.front() == '+') token.remove_prefix(1);
    const char* end = token.data() + token.size();
    const auto result = std::from_chars(token.data(), end, value);
    return result.ec == std::errc() && result.ptr == end;
}

/// Parses the leading integer of an OBJ face corner ("7", "7/2", "7//3", "-1/4/4").
inline bool parse_index(std::string_view token, long long& value) {
    const size_t slash = token.find('/');
    if (slash != std::string_view::npos) token = token.substr(0, slash);
    if (!token.empty() && token.front() == '+') token.remove_prefix(1);
    const char* end = token.data() + token.size();
    const auto result = std::from_chars(token.data(), end, value);
    return !token.empty() && result.ec == std::errc() && result.ptr == end;
}

inline std::string at_line(size_t line, const std::string& what) {
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

/// Whether an OBJ text has an `o` line (then `g` lines do not split objects).
inline bool has_object_lines(const char* data, size_t size) {
    bool found = false;
    for_each_line(data, size, [&](size_t, std::string_view line) {
        line = trim(line);
        if (line.size() >= 2 && line[0] == 'o' && is_space(line[1])) found = true;
        if (line == "o") found = true;
        return !found;
    });
    return found;
}

/// Copies the vertices `faces` (global indices into `vertices`) use into a new object, in the
/// order of their global index, and renumbers the faces locally. `remap` (one entry per global
/// vertex, all -1) is scratch space, returned all -1 again.
inline MeshObject gather(std::string name, const std::vector<double>& vertices,
                  const std::vector<std::int64_t>& faces, std::vector<std::int64_t>& remap) {
    MeshObject object;
    object.name = std::move(name);
    std::vector<std::int64_t> ids;
    for (const std::int64_t global : faces) {
        std::int64_t& slot = remap[static_cast<size_t>(global)];
        if (slot < 0) {
            slot = 0;
            ids.push_back(global);
        }
    }
    std::sort(ids.begin(), ids.end());
    object.vertices.resize(3 * ids.size());
    for (size_t k = 0; k < ids.size(); ++k) {
        remap[static_cast<size_t>(ids[k])] = static_cast<std::int64_t>(k);
        std::memcpy(&object.vertices[3 * k], &vertices[3 * static_cast<size_t>(ids[k])],
                    3 * sizeof(double));
    }
    object.faces.resize(faces.size());
    for (size_t k = 0; k < faces.size(); ++k) object.faces[k] = remap[static_cast<size_t>(faces[k])];
    for (const std::int64_t global : ids) remap[static_cast<size_t>(global)] = -1;
    return object;
}


inline MeshFile parse_obj(const char* data, size_t size) {
    MeshFile file;
    const bool split_on_groups = !has_object_lines(data, size);
    std::vector<double> vertices;
    // per object: name and faces in global (0-based) indices
    std::vector<std::pair<std::string, std::vector<std::int64_t>>> objects(1);
    long long largest = -1;      // the largest positive index seen, 0-based
    size_t largest_line = 0;
    std::vector<std::string_view> tokens;
    std::vector<std::int64_t> corners;

    for_each_line(data, size, [&](size_t line_number, std::string_view line) {
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
            corners.clear();
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
            auto& faces = objects.back().second;
            for (size_t k = 1; k + 1 < corners.size(); ++k) {
                faces.push_back(corners[0]);
                faces.push_back(corners[k]);
                faces.push_back(corners[k + 1]);
            }
        } else if (key == "o" || (split_on_groups && key == "g")) {
            std::string_view name = trim(line);
            name.remove_prefix(1);
            objects.emplace_back(std::string(trim(name)), std::vector<std::int64_t>());
        }
        return true;
    });
    if (!file.error.empty()) return file;
    const long long count = static_cast<long long>(vertices.size() / 3);
    if (largest >= count) {
        file.error = at_line(largest_line, "face index " + std::to_string(largest + 1) +
                                               " but the file has " + std::to_string(count) +
                                               (count == 1 ? " vertex" : " vertices"));
        return file;
    }
    std::vector<std::int64_t> remap(static_cast<size_t>(count), -1);
    for (auto& [name, faces] : objects)
        if (!faces.empty()) file.objects.push_back(gather(std::move(name), vertices, faces, remap));
    return file;
}

}  // namespace reference
