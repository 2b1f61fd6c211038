// The plain manifest reader (manifest_read.hpp): what it passes and the columns it
// gives; everything else is passed over, never read halfway.
#include <cmath>
#include <cstring>
#include <string>

#include "check.hpp"
#include "meshcol/manifest_read.hpp"

using namespace meshcol;

namespace {

const ManifestWords kWords{{"sphere", "box", "capsule", "cylinder", "ellipsoid"},
                           {kRadius, kSize, kRadius | kLength, kRadius | kLength, kSemiAxes},
                           {"xyz", "zyx"},
                           {"decomposed", "hull", "mesh"}};

ManifestColumns read(const std::string& text) { return read_plain_manifest(text, kWords); }

double number(const char* token) {
    double value = std::nan("");
    CHECK(json_number(token, value));
    return value;
}

}  // namespace

TEST_CASE("manifest_read: a plain manifest into columns") {
    const std::string text =
        "\xEF\xBB\xBF{\"units\": \"mm\", \"bodies\": [\n"
        " {\"name\": \"a\", \"primitive\": {\"type\": \"box\", \"size\": [1, 2, 3]},"
        " \"position\": [1.5, -0, 2e1], \"rotation\": {\"quaternion\": [1, 0, 0, 0]}},\n"
        " {\"shape\": \"mesh\", \"primitive\": {\"length\": 2, \"radius\": 0.5, \"type\": "
        "\"capsule\"}, \"name\": \"b\\u00e9\"}], \"duration\": 3}";
    CHECK(!read(text).plain);  // an escape: left to Python
    std::string plain = text;
    plain.replace(plain.find("\\u00e9"), 6, "\xC3\xA9");
    const ManifestColumns c = read(plain);
    CHECK(c.plain);
    CHECK_EQ(c.names.size(), size_t(2));
    CHECK(c.names[1] == "b\xC3\xA9");
    CHECK(c.units == "mm" && c.duration == "3");
    CHECK_EQ(int(c.kinds[0]), 1);
    CHECK_EQ(int(c.kinds[1]), 2);
    CHECK_EQ(c.lengths[2], 3.0);
    CHECK_EQ(c.lengths[3], 0.5);
    CHECK_EQ(c.lengths[4], 2.0);
    CHECK_EQ(c.positions[2], 20.0);
    CHECK(!std::signbit(c.positions[1]));  // "-0" is the integer 0
    CHECK_EQ(c.position_count, size_t(1));
    CHECK_EQ(int(c.rotation[0]), 1);
    CHECK_EQ(int(c.rotation[1]), 0);
    CHECK_EQ(c.quaternions.size(), size_t(4));
    CHECK_EQ(int(c.shapes[0]), -1);
    CHECK_EQ(int(c.shapes[1]), 2);
}

TEST_CASE("manifest_read: anything else is passed over") {
    const std::string body = "{\"name\": \"a\", \"primitive\": {\"type\": \"sphere\", \"radius\": 1}";
    CHECK(read("{\"bodies\": [" + body + "}]}").plain);
    for (const char* tail :
         {", \"mesh\": \"a.obj\"}", ", \"name\": \"b\"}", ", \"position\": [1, 2]}",
          ", \"position\": [NaN, 0, 0]}", ", \"position\": [1e400, 0, 0]}",
          ", \"position\": [01, 0, 0]}", ", \"shape\": \"box\"}", ", \"scale\": 1}",
          ", \"rotation\": {\"euler_deg\": [0, 0, 0]}}", "}, ]", "", "} x"}) {
        CHECK(!read("{\"bodies\": [" + body + tail + "]}").plain);
    }
    CHECK(!read("{\"bodies\": []}").plain);
    CHECK(!read("{\"bodies\": [" + body + "}], \"units\": \"\"}").plain);
    CHECK(!read("{\"bodies\": [{\"name\": \"\xED\xA0\x80\", \"primitive\": {\"type\": "
                "\"sphere\", \"radius\": 1}}]}")
               .plain);  // a UTF-8 surrogate, as Python's codec refuses it
}

TEST_CASE("manifest_read: an ellipsoid's semi-axes are its three lengths") {
    const std::string head = "{\"bodies\": [{\"name\": \"a\", \"primitive\": {\"type\": ";
    const ManifestColumns c = read(head + "\"ellipsoid\", \"semi_axes\": [0.5, 2, 3e-1]}}]}");
    CHECK(c.plain);
    CHECK_EQ(int(c.kinds[0]), 4);
    CHECK_EQ(c.lengths.size(), size_t(3));
    CHECK_EQ(c.lengths[0], 0.5);
    CHECK_EQ(c.lengths[1], 2.0);
    CHECK_EQ(c.lengths[2], 0.3);
    for (const char* rest : {
             "\"ellipsoid\", \"semi_axes\": [1, 0, 1]}}]}",   // zero: Python says so
             "\"ellipsoid\", \"semi_axes\": [1, -1, 1]}}]}",  // negative
             "\"ellipsoid\", \"semi_axes\": [1, 1]}}]}",      // two
             "\"ellipsoid\", \"size\": [1, 1, 1]}}]}",        // a box's field
             "\"ellipsoid\", \"radius\": 1}}]}",
             "\"box\", \"semi_axes\": [1, 1, 1]}}]}",         // an ellipsoid's field
             "\"ellipsoid\", \"semi_axes\": [1, 1, 1], \"size\": [1, 1, 1]}}]}",
             "\"ellipsoid\", \"semi_axes\": [1, 1, 1], \"semi_axes\": [1, 1, 1]}}]}",
             "\"ellipsoid\"}}]}"}) {
        CHECK(!read(head + rest).plain);
    }
}

TEST_CASE("manifest_read: numbers as Python reads them") {
    CHECK_EQ(number("0.1"), 0.1);
    CHECK_EQ(number("-2.5e-3"), -2.5e-3);
    CHECK_EQ(number("123456789012345678901234567890"), 123456789012345678901234567890.0);
    CHECK_EQ(number("0.30000000000000004441"), 0.30000000000000004);
    CHECK(!std::signbit(number("-0")));
    CHECK(std::signbit(number("-0.0")));
    CHECK(std::signbit(number("-0.000000000000000000")));
    double value = 0;
    CHECK(!json_number("1e400", value));
    CHECK(!json_number(std::string(65, '1'), value));
}

TEST_CASE("manifest_read: mesh bodies beside primitive bodies") {
    const ManifestColumns c = read(
        "{\"bodies\": [{\"mesh\": \"assets/a \xC3\xA9.obj\", \"name\": \"a\", \"position\": "
        "[1, 2, 3], \"rotation\": {\"euler_deg\": [0, 0, 90], \"order\": \"zyx\"}},"
        " {\"name\": \"b\", \"primitive\": {\"type\": \"sphere\", \"radius\": 2}},"
        " {\"name\": \"c\", \"shape\": \"hull\", \"mesh\": \"../c.stl\"}]}");
    CHECK(c.plain);
    CHECK_EQ(c.names.size(), size_t(3));
    CHECK_EQ(c.meshes.size(), size_t(3));
    CHECK_EQ(c.mesh_count, size_t(2));
    CHECK(c.meshes[0] == "assets/a \xC3\xA9.obj");
    CHECK(c.meshes[1].empty());
    CHECK(c.meshes[2] == "../c.stl");  // confined, or refused, by Python's loader
    CHECK_EQ(int(c.kinds[0]), -1);
    CHECK_EQ(int(c.kinds[1]), 0);
    CHECK_EQ(int(c.kinds[2]), -1);
    CHECK_EQ(c.lengths.size(), size_t(9));
    CHECK_EQ(c.lengths[0], 0.0);
    CHECK_EQ(c.lengths[3], 2.0);
    CHECK_EQ(c.lengths[6], 0.0);
    CHECK_EQ(int(c.rotation[0]), 2);
    CHECK_EQ(int(c.orders[0]), 1);
    CHECK_EQ(int(c.shapes[2]), 1);
    CHECK_EQ(c.position_count, size_t(1));

    const std::string name = "{\"bodies\": [{\"name\": \"a\", ";
    CHECK(read(name + "\"mesh\": \"a.obj\"}]}").plain);
    for (const char* rest :
         {"\"mesh\": \"\"}]}",                         // empty: Python says so
          "\"mesh\": \"a\\u002eobj\"}]}",              // an escape: left to Python
          "\"mesh\": \"a\\\\b.obj\"}]}",               // an escaped backslash
          "\"mesh\": \"a\tb.obj\"}]}",                 // a raw control character
          "\"mesh\": \"\xC3\x28.obj\"}]}",             // not UTF-8
          "\"mesh\": 1}]}", "\"mesh\": null}]}", "\"mesh\": [\"a.obj\"]}]}",
          "\"mesh\": \"a.obj\", \"mesh\": \"b.obj\"}]}",  // Python keeps the last
          "\"mesh\": \"a.obj\", \"primitive\": {\"type\": \"sphere\", \"radius\": 1}}]}",
          "\"mesh\": \"a.obj\", \"scale\": 2}]}", "\"mesh\": \"a.obj\", \"velocity\": [0, 0, 0]}]}",
          "\"mesh\": \"a.obj\"", "\"mesh\": \"a.obj}]}"}) {
        CHECK(!read(name + rest).plain);
    }
}
