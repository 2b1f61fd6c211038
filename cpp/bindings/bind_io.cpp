// Exposes mesh_read.hpp: the fast OBJ/STL readers, batched over files, and the vertex merge.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "meshcol/mesh_read.hpp"
#include "ndarray.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

using VertexArray = Out<double, -1, 3>;
using FaceArray = Out<std::int64_t, -1, 3>;
using IndexArray = Out<std::int64_t, -1>;

auto read_files(const std::vector<std::string>& paths, const std::vector<int>& formats, bool merge,
                int threads) {
    if (formats.size() != paths.size())
        throw std::invalid_argument("formats must have one entry per path");
    std::vector<meshcol::MeshFormat> kinds;
    for (int f : formats) {
        if (f != 0 && f != 1) throw std::invalid_argument("format must be 0 (OBJ) or 1 (STL)");
        kinds.push_back(static_cast<meshcol::MeshFormat>(f));
    }
    std::vector<meshcol::MeshFile> files;
    {
        nb::gil_scoped_release release;
        files = meshcol::read_mesh_files(paths, kinds, merge, threads);
    }
    std::vector<double> vertices;
    std::vector<std::int64_t> faces;
    std::vector<std::int64_t> vertex_offsets{0}, face_offsets{0}, object_file;
    std::vector<std::string> names, errors;
    std::vector<std::int8_t> status;
    size_t total_v = 0, total_f = 0, total_o = 0;
    for (const meshcol::MeshFile& file : files)
        for (const meshcol::MeshObject& o : file.objects) {
            total_v += o.vertices.size();
            total_f += o.faces.size();
            ++total_o;
        }
    vertices.reserve(total_v);  // one allocation each: 100,000 files append without regrowth
    faces.reserve(total_f);
    vertex_offsets.reserve(total_o + 1);
    face_offsets.reserve(total_o + 1);
    object_file.reserve(total_o);
    names.reserve(total_o);
    errors.reserve(files.size());
    status.reserve(files.size());
    for (size_t i = 0; i < files.size(); ++i) {
        errors.push_back(std::move(files[i].error));
        status.push_back(static_cast<std::int8_t>(files[i].status));
        for (meshcol::MeshObject& o : files[i].objects) {
            vertices.insert(vertices.end(), o.vertices.begin(), o.vertices.end());
            faces.insert(faces.end(), o.faces.begin(), o.faces.end());
            vertex_offsets.push_back(static_cast<std::int64_t>(vertices.size() / 3));
            face_offsets.push_back(static_cast<std::int64_t>(faces.size() / 3));
            object_file.push_back(static_cast<std::int64_t>(i));
            names.push_back(std::move(o.name));
        }
        files[i].objects.clear();
    }
    const size_t v = vertices.size() / 3, f = faces.size() / 3, o = object_file.size();
    // Names and messages carry bytes of the file (an object name, a bad token) in whatever
    // encoding it has: bytes, decoded in Python (UTF-8, else Latin-1), never a decode error here.
    nb::list name_bytes, error_bytes;
    for (const std::string& name : names) name_bytes.append(nb::bytes(name.data(), name.size()));
    for (const std::string& error : errors) error_bytes.append(nb::bytes(error.data(), error.size()));
    return std::make_tuple(vector_array<VertexArray>(std::move(vertices), v, 3),
                           vector_array<FaceArray>(std::move(faces), f, 3),
                           vector_array<IndexArray>(std::move(vertex_offsets), o + 1, 0),
                           vector_array<IndexArray>(std::move(face_offsets), o + 1, 0),
                           vector_array<IndexArray>(std::move(object_file), o, 0), name_bytes,
                           vector_array<Out<std::int8_t, -1>>(std::move(status), files.size(), 0),
                           error_bytes);
}

auto merge(Points vertices, Faces faces, int digits) {
    const std::int64_t n = static_cast<std::int64_t>(vertices.shape(0));
    std::vector<double> v(vertices.data(), vertices.data() + 3 * vertices.shape(0));
    std::vector<std::int64_t> f(faces.data(), faces.data() + 3 * faces.shape(0));
    for (const std::int64_t index : f)
        if (index < 0 || index >= n)
            throw std::invalid_argument("face index " + std::to_string(index) +
                                        " out of range [0, " + std::to_string(n) + ")");
    {
        nb::gil_scoped_release release;
        meshcol::merge_vertices(v, f, digits);
    }
    const size_t rows = v.size() / 3, face_rows = f.size() / 3;
    return std::make_tuple(vector_array<VertexArray>(std::move(v), rows, 3),
                           vector_array<FaceArray>(std::move(f), face_rows, 3));
}

auto identities(const std::vector<std::string>& paths, int threads) {
    const size_t n = paths.size();
    std::vector<std::uint64_t> device(n), inode(n);
    std::vector<std::uint8_t> found(n);
    {
        nb::gil_scoped_release release;
        meshcol::file_identities(paths, threads, device.data(), inode.data(), found.data());
    }
    return std::make_tuple(vector_array<Out<std::uint64_t, -1>>(std::move(device), n, 0),
                           vector_array<Out<std::uint64_t, -1>>(std::move(inode), n, 0),
                           vector_array<Out<std::uint8_t, -1>>(std::move(found), n, 0));
}

}  // namespace

void bind_io(nb::module_& m) {
    m.def("read_mesh_files", &read_files, "paths"_a, "formats"_a, "merge"_a = true,
          "threads"_a = 0,
          "Reads OBJ (format 0) and STL (format 1) files in parallel. Returns (vertices (V, 3), "
          "faces (F, 3) local to each object, vertex_offsets (O + 1,), face_offsets (O + 1,), "
          "object_file (O,), object names (bytes), status (N,) int8 per file (0 read, 1 not found, 2 a "
          "directory, 3 unreadable, 4 corrupt), one message per file ('' when read)).");
    m.def("file_identities", &identities, "paths"_a, "threads"_a = 0,
          "Device and inode of each path, symbolic links followed, stat'ed in parallel. Returns "
          "(device (N,) uint64, inode (N,) uint64, found (N,) uint8: 0 where stat fails).");
    m.def("merge_vertices", &merge, "vertices"_a, "faces"_a, "digits"_a = 8,
          "Merges vertices equal after rounding to `digits` decimals (trimesh's rule), drops "
          "unused ones, renumbers faces. Returns (vertices, faces).");
}
