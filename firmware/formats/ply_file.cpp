#include "firmware/formats/ply_file.hpp"

#include "firmware/formats/atomic_file.hpp"

#include <bit>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace stria::firmware {
namespace {

static_assert(std::endian::native == std::endian::little, "binary PLY is written in host order: little-endian only");

constexpr const char* kProperties = "property float x\n"
                                    "property float y\n"
                                    "property float z\n"
                                    "property float u\n"
                                    "property float v\n"
                                    "property int edge\n"
                                    "end_header\n";
constexpr std::size_t kBinaryVertexBytes = 6 * 4;

std::string header(std::size_t count, bool ascii)
{
    return std::string("ply\nformat ") + (ascii ? "ascii" : "binary_little_endian") +
           " 1.0\ncomment stria scan: x y z in mm (camera frame), u v camera pixel, edge = pattern edge\n"
           "element vertex " + std::to_string(count) + "\n" + kProperties;
}

}  // namespace

Status writePly(const std::string& path, std::span<const pipeline::ScanPoint> points, bool ascii)
{
    auto file = AtomicFile::create(path);
    if (!file) return file.status();
    const std::string head = header(points.size(), ascii);
    if (Status s = file->write(head.data(), head.size()); !s) return s;
    std::string body;
    if (ascii) {
        char line[160];
        for (const pipeline::ScanPoint& p : points) {
            const int n = std::snprintf(line, sizeof line, "%.9g %.9g %.9g %.9g %.9g %d\n", p.position[0], p.position[1],
                                        p.position[2], p.pixel.x, p.pixel.y, static_cast<int>(p.edge));
            body.append(line, static_cast<std::size_t>(n));
        }
    } else {
        body.resize(points.size() * kBinaryVertexBytes);
        char* out = body.data();
        for (const pipeline::ScanPoint& p : points) {
            const float values[5] = {p.position[0], p.position[1], p.position[2], p.pixel.x, p.pixel.y};
            std::memcpy(out, values, sizeof values);
            const std::int32_t edge = p.edge;
            std::memcpy(out + sizeof values, &edge, sizeof edge);
            out += kBinaryVertexBytes;
        }
    }
    if (Status s = file->write(body.data(), body.size()); !s) return s;
    return file->commit();
}

Result<std::vector<pipeline::ScanPoint>> readPly(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) return Status::error("PLY '" + path + "': cannot open: " + std::strerror(errno));
    auto fail = [&](const std::string& what) { return Status::error("PLY '" + path + "': " + what); };

    std::string line;
    if (!std::getline(in, line) || line != "ply") return fail("not a PLY file (first line is not 'ply')");
    bool ascii = false;
    long count = -1;
    std::string properties;
    while (std::getline(in, line)) {
        if (line == "end_header") break;
        std::istringstream words(line);
        std::string keyword;
        words >> keyword;
        if (keyword == "format") {
            std::string format;
            words >> format;
            if (format == "ascii") ascii = true;
            else if (format != "binary_little_endian") return fail("unsupported format '" + format + "'");
        } else if (keyword == "element") {
            std::string name;
            words >> name >> count;
            if (name != "vertex" || count < 0) return fail("expected 'element vertex N', found '" + line + "'");
        } else if (keyword == "property") {
            properties += line + "\n";
        } else if (keyword != "comment") {
            return fail("unexpected header line '" + line + "'");
        }
    }
    if (line != "end_header") return fail("the header has no end_header");
    if (count < 0) return fail("the header has no vertex element");
    if (properties + "end_header\n" != kProperties)
        return fail("the vertex properties are not x y z u v (float) edge (int) as stria writes them");

    std::vector<pipeline::ScanPoint> points(static_cast<std::size_t>(count));
    for (long i = 0; i < count; ++i) {
        pipeline::ScanPoint& p = points[static_cast<std::size_t>(i)];
        if (ascii) {
            if (!(in >> p.position[0] >> p.position[1] >> p.position[2] >> p.pixel.x >> p.pixel.y >> p.edge))
                return fail("vertex " + std::to_string(i) + " of " + std::to_string(count) + " is missing or malformed");
        } else {
            char raw[kBinaryVertexBytes];
            if (!in.read(raw, sizeof raw))
                return fail("the file ends at vertex " + std::to_string(i) + " of " + std::to_string(count));
            float values[5];
            std::memcpy(values, raw, sizeof values);
            std::memcpy(&p.edge, raw + sizeof values, sizeof p.edge);
            p.position = {values[0], values[1], values[2]};
            p.pixel = {values[3], values[4]};
        }
    }
    return points;
}

}  // namespace stria::firmware
