// OBJ and STL readers and the vertex merge (mesh_read.hpp): what they read, and the status and
// one-line message of every kind of bad input.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <random>

#include "check.hpp"
#include "meshcol/mesh_read.hpp"
#include "obj_reference.hpp"

using namespace meshcol;

namespace {

MeshFile obj(const std::string& text) { return parse_obj(text.data(), text.size()); }
MeshFile stl(const std::string& bytes) { return parse_stl(bytes.data(), bytes.size()); }

bool starts_with(const std::string& text, const std::string& prefix) {
    return text.compare(0, prefix.size(), prefix) == 0;
}

// A binary STL of `count` triangles, each the triangle (0,0,0), (1,0,0), (0,1,0) moved by t.
std::string binary_stl(std::uint32_t count) {
    std::string bytes(84 + 50 * static_cast<size_t>(count), '\0');
    std::memcpy(&bytes[80], &count, 4);
    for (std::uint32_t t = 0; t < count; ++t) {
        const float corners[9] = {0, 0, float(t), 1, 0, float(t), 0, 1, float(t)};
        std::memcpy(&bytes[84 + 50 * static_cast<size_t>(t) + 12], corners, sizeof corners);
    }
    return bytes;
}

// A file in a fresh temporary folder, removed with it.
struct TemporaryFolder {
    std::filesystem::path path;
    TemporaryFolder() {
        path = std::filesystem::temp_directory_path() /
               ("meshcol_cpp_tests_" + std::to_string(reinterpret_cast<std::uintptr_t>(this)));
        std::filesystem::create_directories(path);
    }
    ~TemporaryFolder() { std::filesystem::remove_all(path); }
    std::string write(const std::string& name, const std::string& bytes) const {
        const std::string file = (path / name).string();
        std::FILE* stream = std::fopen(file.c_str(), "wb");
        if (stream != nullptr) {
            std::fwrite(bytes.data(), 1, bytes.size(), stream);
            std::fclose(stream);
        }
        return file;
    }
};

}  // namespace

TEST_CASE("mesh read: an OBJ quad, objects, negative indices") {
    const MeshFile quad = obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
    REQUIRE(quad.error.empty());
    REQUIRE(quad.objects.size() == 1);
    CHECK_EQ(quad.objects[0].faces.size(), size_t{6});  // a fan of two triangles
    CHECK_EQ(quad.objects[0].vertices.size(), size_t{12});

    const MeshFile two = obj("o first\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n"
                             "o second\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4/1/1 5//2 6\no empty\n");
    REQUIRE(two.error.empty());
    REQUIRE(two.objects.size() == 2);  // an object without a face is dropped
    CHECK_EQ(two.objects[0].name, std::string("first"));
    CHECK_EQ(two.objects[1].name, std::string("second"));
    CHECK((two.objects[1].faces == std::vector<std::int64_t>{0, 1, 2}));  // local indices
}

TEST_CASE("mesh read: corrupt OBJ files name the line and the fault") {
    const MeshFile zero = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
    CHECK_EQ(zero.error, std::string("line 4: face index 0 (OBJ indices start at 1)"));
    const MeshFile beyond = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    CHECK_EQ(beyond.error, std::string("line 4: face index 9 but the file has 3 vertices"));
    const MeshFile short_vertex = obj("v 0 0\n");
    CHECK_EQ(short_vertex.error, std::string("line 1: a vertex needs three coordinates"));
    const MeshFile infinite = obj("v 0 0 inf\n");
    CHECK_EQ(infinite.error, std::string("line 1: non-finite vertex coordinate"));
    CHECK(starts_with(obj("v 0 0 zero\n").error, "line 1: vertex coordinate 'zero'"));
    CHECK(obj("").error.empty());  // an empty file is read: no objects
    CHECK(obj("").objects.empty());
}

TEST_CASE("mesh read: binary and ASCII STL") {
    const MeshFile binary = stl(binary_stl(3));
    REQUIRE(binary.error.empty());
    REQUIRE(binary.objects.size() == 1);
    CHECK_EQ(binary.objects[0].faces.size(), size_t{9});
    CHECK_EQ(binary.objects[0].vertices[9 * 2 + 2], 2.0);

    const MeshFile ascii = stl("solid part\n facet normal 0 0 1\n  outer loop\n"
                               "   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n"
                               "  endloop\n endfacet\nendsolid part\n");
    REQUIRE(ascii.error.empty());
    REQUIRE(ascii.objects.size() == 1);
    CHECK_EQ(ascii.objects[0].name, std::string("part"));
    CHECK_EQ(ascii.objects[0].faces.size(), size_t{3});
}

TEST_CASE("mesh read: corrupt STL files say why") {
    std::string truncated = binary_stl(4);
    truncated.resize(truncated.size() - 7);
    truncated[0] = '\0';  // binary header, but the size does not match the count
    CHECK(starts_with(stl(truncated).error, "neither binary STL"));
    CHECK(starts_with(stl("hello world, no solid here").error, "neither binary STL"));
    std::string nan_corner = binary_stl(2);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(&nan_corner[84 + 50 + 12 + 4], &nan, 4);
    CHECK_EQ(stl(nan_corner).error, std::string("triangle 1 has a non-finite vertex coordinate"));
    // a loop left open by one solid and closed in the next: an error, never a face that
    // indexes before the second solid's vertices (it crashed the vertex merge)
    const MeshFile split = stl("solid a\n vertex 0 0 0\n vertex 1 0 0\n vertex 0 1 0\n"
                               "solid b\n endloop\nendsolid\n");
    CHECK_EQ(split.error, std::string("line 6: a facet has 0 vertices, not 3"));
    // an empty file read into a null buffer: refused, without passing null to memchr (UBSan)
    CHECK(starts_with(parse_stl(nullptr, 0).error, "neither binary STL"));
}

TEST_CASE("mesh read: files read in parallel, each with its status") {
    const TemporaryFolder folder;
    const std::string good = folder.write("good.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 0\nf 1 2 3\nf 4 2 3\n");
    const std::string bad = folder.write("bad.stl", "solid x\n outer loop\n vertex 0 0 0\n endloop\nendsolid\n");
    const std::string empty = folder.write("empty.stl", "");
    const std::string missing = (folder.path / "missing.obj").string();
    const std::string directory = folder.path.string();
    const std::vector<MeshFile> files = read_mesh_files(
        {good, bad, empty, missing, directory},
        {MeshFormat::Obj, MeshFormat::Stl, MeshFormat::Stl, MeshFormat::Obj, MeshFormat::Obj}, true, 2);
    REQUIRE(files.size() == 5);
    CHECK(files[0].status == ReadStatus::Ok);
    REQUIRE(files[0].objects.size() == 1);
    CHECK_EQ(files[0].objects[0].vertices.size(), size_t{9});  // vertex 4 merged into vertex 1
    CHECK(files[1].status == ReadStatus::Corrupt);
    CHECK(files[2].status == ReadStatus::Corrupt);  // an empty STL is neither kind
    CHECK(files[3].status == ReadStatus::NotFound);
    CHECK_EQ(files[3].error, std::string("file not found"));
    CHECK(files[4].status == ReadStatus::Directory);
}

TEST_CASE("mesh read: files read with kept working arrays are each read alone") {
    // A reader thread keeps its arrays and its folder's descriptor from file to file: every
    // file of a long list (big after small, several objects after one, faults between, files
    // of two folders interleaved) reads as it does alone.
    const TemporaryFolder one, two;
    std::vector<std::string> paths;
    std::mt19937 random(7);
    for (int k = 0; k < 60; ++k) {
        std::string text;
        const int points = 3 + static_cast<int>(random() % 40);
        for (int p = 0; p < points; ++p)
            text += "v " + std::to_string(random() % 1000 * 1e-3) + " " + std::to_string(p) +
                    " " + std::to_string(k) + "\n";
        if (k % 7 == 3) text += "o second\n";
        for (int p = 2; p < points; ++p)
            text += "f 1 " + std::to_string(p) + " " + std::to_string(p + 1) + "\n";
        if (k % 11 == 5) text += "f 1 2 999\n";
        paths.push_back((k % 2 ? one : two).write("f" + std::to_string(k) + ".obj", text));
    }
    paths.push_back((one.path / "missing.obj").string());
    const std::vector<MeshFormat> formats(paths.size(), MeshFormat::Obj);
    for (const int threads : {1, 3}) {
        const std::vector<MeshFile> files = read_mesh_files(paths, formats, true, threads);
        for (size_t i = 0; i < paths.size(); ++i) {
            const MeshFile alone = read_mesh_files({paths[i]}, {MeshFormat::Obj}, true, 1)[0];
            CHECK(files[i].status == alone.status);
            CHECK_EQ(files[i].error, alone.error);
            REQUIRE(files[i].objects.size() == alone.objects.size());
            for (size_t o = 0; o < alone.objects.size(); ++o) {
                CHECK(files[i].objects[o].vertices == alone.objects[o].vertices);
                CHECK(files[i].objects[o].faces == alone.objects[o].faces);
                CHECK_EQ(files[i].objects[o].name, alone.objects[o].name);
            }
        }
        // packed: each object's arrays in order, its file and its largest |coordinate|
        std::vector<MeshFile> copy = files;
        const std::vector<PackedStart> starts = packed_starts(copy);
        const PackedStart total = starts.back();
        std::vector<double> vertices(3 * static_cast<size_t>(total.vertex));
        std::vector<std::int32_t> faces(3 * static_cast<size_t>(total.face));
        std::vector<std::int64_t> v_off(static_cast<size_t>(total.object) + 1);
        std::vector<std::int64_t> f_off(v_off.size()), owner(v_off.size() - 1);
        std::vector<double> largest(owner.size());
        pack_mesh_files(copy, starts, threads, vertices.data(), faces.data(), v_off.data(),
                        f_off.data(), owner.data(), largest.data());
        size_t k = 0;
        for (size_t i = 0; i < files.size(); ++i)
            for (const MeshObject& object : files[i].objects) {
                CHECK_EQ(owner[k], static_cast<std::int64_t>(i));
                const std::vector<double> got(vertices.begin() + 3 * v_off[k],
                                              vertices.begin() + 3 * v_off[k + 1]);
                CHECK(got == object.vertices);
                const std::vector<std::int64_t> got_faces(faces.begin() + 3 * f_off[k],
                                                          faces.begin() + 3 * f_off[k + 1]);
                CHECK(got_faces == object.faces);
                double top = 0;
                for (const double v : object.vertices) top = std::max(top, std::fabs(v));
                CHECK_EQ(largest[k], top);
                CHECK(copy[i].objects[&object - files[i].objects.data()].vertices.empty());
                ++k;
            }
        CHECK_EQ(k, owner.size());
    }
}

TEST_CASE("mesh read: merge_vertices rounds to the digits and renumbers") {
    std::vector<double> vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1e-10, 0, 0, 5, 5, 5};
    std::vector<std::int64_t> faces = {0, 1, 2, 3, 2, 1};  // vertex 4 unused
    merge_vertices(vertices, faces, 8);
    CHECK_EQ(vertices.size(), size_t{9});
    CHECK((faces == std::vector<std::int64_t>{0, 1, 2, 0, 2, 1}));
    // negative coordinates (their keys were a left shift of a negative value: undefined),
    // and one too large to round, which merges only with itself
    std::vector<double> signed_vertices = {-0.85, -1, -2, 1e300, 0, 0, -0.850000001, -1, -2, 1e300, 0, 0};
    std::vector<std::int64_t> signed_faces = {0, 1, 2, 2, 3, 1};
    merge_vertices(signed_vertices, signed_faces, 8);
    CHECK_EQ(signed_vertices.size(), size_t{6});
    CHECK((signed_faces == std::vector<std::int64_t>{0, 1, 0, 0, 1, 1}));
}

TEST_CASE("mesh read: an ASCII STL cut inside a facet is refused, naming the loop") {
    const MeshFile cut = stl("solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n");
    CHECK_EQ(cut.error, std::string("line 3: the file ends inside this facet's loop (cut short?)"));
    const MeshFile whole =
        stl("solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
            "endloop\nendfacet\n");  // cut after a whole triangle: nothing of it is lost
    CHECK(whole.error.empty());
    CHECK_EQ(whole.objects.size(), size_t(1));
}

namespace {

// A random OBJ text of a few lines drawn from well-formed and broken lines alike: spaces, tabs
// and CRs, comments, backslash continuations, objects and groups, every kind of bad token.
std::string random_obj(std::mt19937& rng) {
    static const char* const lines[] = {
        "v 0 0 0", "v 1 0 0", "v 0 1 0", "v 0 0 1", "v 1.5 -2e-3 +7", "v 1 2 3 0.5 0.5 0.5",
        "v 1 2", "v", "v 1 2 x", "v 1 nan 0", "v inf 0 0", "v 1 2 3#c", "v 1 2#c 3", "v#c",
        "v +-1 2 3", "v ++1 2 3", "v 1e400 0 0", "v .5 5. 0x1", "v1 2 3", "vt 0 0", "vn 0 0 1",
        "f 1 2 3", "f 1/1/1 2//2 3/3", "f -1 -2 -3", "f -3 -2 -1 -4", "f 0 1 2", "f 1 2 99",
        "f +1 2 3 4 5", "f 1 a 2", "f 1 2", "f", "f 1/ 2/x 3//", "f /1 2 3", "f 1 2 3#c",
        "f 1 2#c 3", "f 99999999999999999999 1 2", "f -9 1 2", "f 1 2 -0", "f 2 3 4 1",
        "o first", "o", "o#x", "obj x", "o  spaced  name  ", "g group", "g", "g a b",
        "# comment", "", "   ", "usemtl m", "s off", "mtllib x.mtl", "f 1 2 \\", "v 0 \\",
        "l 1 2", "o \\", "p 1"};
    std::uniform_int_distribution<size_t> pick(0, sizeof lines / sizeof lines[0] - 1);
    std::uniform_int_distribution<int> count(1, 14), lead(0, 5);
    std::string text;
    const int n = count(rng);
    for (int k = 0; k < n; ++k) {
        const int pad = lead(rng);
        if (pad == 4) text += "  ";
        if (pad == 5) text += "\t";
        if (lead(rng) == 0) {  // a vertex of random decimals: 1-20 digits, a point anywhere
            text += "v";
            std::uniform_int_distribution<int> digit(0, 9), length(1, 20), sign(0, 3);
            for (int c = 0; c < 3; ++c) {
                const int digits = length(rng);
                std::uniform_int_distribution<int> point(-1, digits);
                const int at = point(rng);
                text += sign(rng) == 0 ? " -" : sign(rng) == 1 ? " +" : " ";
                for (int d = 0; d < digits; ++d) {
                    if (d == at) text += ".";
                    text += static_cast<char>('0' + digit(rng));
                }
                if (at == digits) text += ".";
            }
        } else {
            text += lines[pick(rng)];
        }
        if (pad == 3) text += " \r";
        text += k + 1 < n || pad != 2 ? "\n" : "";
    }
    return text;
}

}  // namespace

TEST_CASE("mesh read: the one-pass OBJ parser reads as the tokenizing one did, faults too") {
    std::mt19937 rng(20260512);
    for (int round = 0; round < 20000; ++round) {
        const std::string text = random_obj(rng);
        const MeshFile got = obj(text);
        const MeshFile want = reference::parse_obj(text.data(), text.size());
        bool same = got.error == want.error && got.objects.size() == want.objects.size();
        for (size_t k = 0; same && k < got.objects.size(); ++k) {
            const auto& a = got.objects[k].vertices;
            const auto& b = want.objects[k].vertices;
            same = got.objects[k].name == want.objects[k].name &&
                   got.objects[k].faces == want.objects[k].faces && a.size() == b.size() &&
                   std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
        }
        if (!same)
            std::fprintf(stderr, "differs on:\n%s\n(error '%s', reference '%s')\n", text.c_str(),
                         got.error.c_str(), want.error.c_str());
        REQUIRE(same);
    }
}
