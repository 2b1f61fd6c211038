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
#include "meshcol/point_sets.hpp"
#include "ndarray.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

using VertexArray = Out<double, -1, 3>;
using FaceArray = Out<std::int64_t, -1, 3>;
using PackedFaceArray = Out<std::int32_t, -1, 3>;  // read_mesh_files' (mesh_read.hpp)
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
    std::vector<meshcol::PackedStart> starts;
    {
        nb::gil_scoped_release release;
        files = meshcol::read_mesh_files(paths, kinds, merge, threads);
        starts = meshcol::packed_starts(files);
    }
    const meshcol::PackedStart total = starts.back();
    const size_t v = static_cast<size_t>(total.vertex), f = static_cast<size_t>(total.face),
                 o = static_cast<size_t>(total.object);
    auto vertices = new_array<VertexArray>({v, 3});
    auto faces = new_array<PackedFaceArray>({f, 3});
    auto vertex_offsets = new_array<IndexArray>({o + 1});
    auto face_offsets = new_array<IndexArray>({o + 1});
    auto object_file = new_array<IndexArray>({o});
    auto largest = new_array<Out<double, -1>>({o});
    auto status = new_array<Out<std::int8_t, -1>>({files.size()});
    {
        // one copy into numpy's arrays, on the core's threads (each file's objects freed as
        // they are copied): 100,000 files' vertices and faces are a few hundred MB
        nb::gil_scoped_release release;
        meshcol::pack_mesh_files(files, starts, threads, vertices.data(), faces.data(),
                                 vertex_offsets.data(), face_offsets.data(), object_file.data(),
                                 largest.data());
        for (size_t i = 0; i < files.size(); ++i)
            status.data()[i] = static_cast<std::int8_t>(files[i].status);
    }
    // Names and messages carry bytes of the file (an object name, a bad token) in whatever
    // encoding it has: bytes, decoded in Python (UTF-8, else Latin-1), never a decode error here.
    nb::list name_bytes, error_bytes;
    for (const meshcol::MeshFile& file : files) {
        error_bytes.append(nb::bytes(file.error.data(), file.error.size()));
        for (const meshcol::MeshObject& object : file.objects)
            name_bytes.append(nb::bytes(object.name.data(), object.name.size()));
    }
    return std::make_tuple(vertices, faces, vertex_offsets, face_offsets, object_file, name_bytes,
                           status, error_bytes, largest);
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

auto fingerprints(Points points, Index64 offsets, int threads) {
    const size_t sets = offsets.shape(0) == 0 ? 0 : offsets.shape(0) - 1;
    const std::int64_t* o = offsets.data();
    const std::int64_t rows = static_cast<std::int64_t>(points.shape(0));
    for (size_t s = 0; s < sets; ++s)
        if (o[s] < 0 || o[s + 1] < o[s] || o[s + 1] > rows)
            throw std::invalid_argument("offsets must rise from 0 within the points");
    auto out = new_array<Out<std::uint64_t, -1>>({sets});
    {
        nb::gil_scoped_release release;
        meshcol::point_set_fingerprints(points.data(), o, static_cast<std::int64_t>(sets), threads,
                                        out.data());
    }
    return out;
}

}  // namespace

void bind_io(nb::module_& m) {
    m.def("read_mesh_files", &read_files, "paths"_a, "formats"_a, "merge"_a = true,
          "threads"_a = 0,
          "Reads OBJ (format 0) and STL (format 1) files in parallel. Returns (vertices (V, 3), "
          "faces (F, 3) int32 local to each object, vertex_offsets (O + 1,), face_offsets (O + 1,), "
          "object_file (O,), object names (bytes), status (N,) int8 per file (0 read, 1 not found, 2 a "
          "directory, 3 unreadable, 4 corrupt), one message per file ('' when read), the largest "
          "|coordinate| of each object (O,), 0 without vertices).");
    m.def("file_identities", &identities, "paths"_a, "threads"_a = 0,
          "Device and inode of each path, symbolic links followed, stat'ed in parallel. Returns "
          "(device (N,) uint64, inode (N,) uint64, found (N,) uint8: 0 where stat fails).");
    m.def("point_set_fingerprints", &fingerprints, "points"_a, "offsets"_a, "threads"_a = 0,
          "The fingerprint (uint64) of each point set packed in points (V, 3), set s being rows "
          "offsets[s]:offsets[s + 1]: see meshcol/point_sets.hpp (bulk colliders find repeats "
          "with it, then compare the bits).");
    m.def("merge_vertices", &merge, "vertices"_a, "faces"_a, "digits"_a = 8,
          "Merges vertices equal after rounding to `digits` decimals (trimesh's rule), drops "
          "unused ones, renumbers faces. Returns (vertices, faces).");
}
