#pragma once
/// Fast readers for the common mesh formats (OBJ, binary and ASCII STL), geometry only, and the
/// one vertex merge of the package. Files are read and parsed in parallel; a file that cannot
/// be read or parsed gets a one-line message (with the line number for text formats) instead
/// of objects. Everything else (materials, normals, texture coordinates, colours) is skipped.

#include <cstdint>
#include <string>
#include <vector>

namespace meshcol {

/// One object of a mesh file: an OBJ object (or group, when the file has no objects), an
/// ASCII STL solid, or the one mesh of a binary STL.
struct MeshObject {
    std::string name;                  ///< as the file spells it; "" when the file gives none
    std::vector<double> vertices;      ///< 3 per vertex
    std::vector<std::int64_t> faces;   ///< 3 per triangle, into this object's vertices
};

/// Why a file gave no objects.
enum class ReadStatus : std::int8_t {
    Ok = 0,           ///< read and parsed (possibly with no faces)
    NotFound = 1,     ///< no such file
    Directory = 2,    ///< a directory
    Unreadable = 3,   ///< exists but cannot be read (permissions, I/O error)
    Corrupt = 4,      ///< read, but not a valid file of its format
};

/// What one file gave.
struct MeshFile {
    std::vector<MeshObject> objects;   ///< in file order; objects without a face are dropped
    ReadStatus status = ReadStatus::Ok;
    std::string error;                 ///< empty when Ok; else what is wrong, in one line
};

enum class MeshFormat : int { Obj = 0, Stl = 1 };

/// Parses OBJ text. Polygons are fan-triangulated; indices may be negative (relative) but never
/// 0 or out of range; `v` lines need three finite coordinates. `o` lines start objects; when
/// the file has no `o` line, `g` lines do. Faces before the first of them form an object
/// named "".
MeshFile parse_obj(const char* data, size_t size);

/// Parses a binary STL (size = 84 + 50 x count) or an ASCII STL (one object per solid).
/// Corners are not shared: merge them with `merge_vertices`.
MeshFile parse_stl(const char* data, size_t size);

/// Reads and parses `paths` (formats given per file) on `threads` threads (0: all cores).
std::vector<MeshFile> read_mesh_files(const std::vector<std::string>& paths,
                                      const std::vector<MeshFormat>& formats, bool merge,
                                      int threads);

/// Where each file's objects go in the packed arrays of `pack_mesh_files`: `starts[i]` holds
/// file i's first object, vertex and face (3 counts), `starts[n]` the totals.
struct PackedStart {
    std::int64_t object = 0, vertex = 0, face = 0;
};
std::vector<PackedStart> packed_starts(const std::vector<MeshFile>& files);

/// Copies every object of `files` (in file order, each file's in its order) into packed
/// arrays sized by `packed_starts` (its last entry): `vertices` (3 per vertex), `faces` (3 per
/// triangle, local to the object, as int32: half the memory of a scene's largest array, and
/// every index of a file within `max_mesh_file_bytes` fits), `vertex_offsets` and `face_offsets` (objects + 1 entries,
/// from 0), `object_file` (the file of each object) and `largest` (the largest |coordinate|
/// of each object, 0 without vertices; NaN when a coordinate is NaN). On `threads` threads;
/// each object's vertices and faces are freed once copied (its name is kept).
void pack_mesh_files(std::vector<MeshFile>& files, const std::vector<PackedStart>& starts,
                     int threads, double* vertices, std::int32_t* faces,
                     std::int64_t* vertex_offsets, std::int64_t* face_offsets,
                     std::int64_t* object_file, double* largest);

/// Device and inode of each of `paths` (symbolic links followed, as stat does), on `threads`
/// threads (0: all cores); `found[i]` is 0 where the path names nothing stat can reach. What
/// tells whether an output is one of a run's 100,000 input files, without reading them.
void file_identities(const std::vector<std::string>& paths, int threads, std::uint64_t* device,
                     std::uint64_t* inode, std::uint8_t* found);

/// Merges vertices whose coordinates round to the same multiple of 10^-digits, keeps only the
/// vertices faces use, in the order of their first index, and renumbers the faces (none is
/// removed). The rounding is trimesh's (`round(x * 10^digits - 1e-6)`), so watertightness
/// agrees with trimesh; a coordinate too large for the rounding only merges with itself.
void merge_vertices(std::vector<double>& vertices, std::vector<std::int64_t>& faces,
                    int digits);

}  // namespace meshcol
