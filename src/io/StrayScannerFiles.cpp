#include "StrayScannerFiles.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <map>
#include <utility>

#include "TextParsing.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace stray_scanner {

namespace {

// Commas become blanks, so that "1.5, 2" and "1.5 2" read alike.
std::vector<std::string_view> splitCsv(std::string& line) {
    std::replace(line.begin(), line.end(), ',', ' ');
    return text::splitWhitespace(line);
}

std::string lowercase(std::string_view token) {
    std::string s(token);
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}

// Where each odometry field is, by column.
struct OdometryColumns {
    static constexpr int kUnset = -1;
    int timestamp = 0, frame = 1, x = 2, y = 3, z = 4, qx = 5, qy = 6, qz = 7, qw = 8;
    int count = 9;

    // From a header line; throws naming the first missing column.
    static OdometryColumns fromHeader(const std::vector<std::string_view>& names, const std::string& path, int line) {
        OdometryColumns c;
        c.count = int(names.size());
        const std::array<std::pair<const char*, int*>, 9> fields = {{{"timestamp", &c.timestamp},
                                                                     {"frame", &c.frame},
                                                                     {"x", &c.x},
                                                                     {"y", &c.y},
                                                                     {"z", &c.z},
                                                                     {"qx", &c.qx},
                                                                     {"qy", &c.qy},
                                                                     {"qz", &c.qz},
                                                                     {"qw", &c.qw}}};
        for (const auto& [name, column] : fields) {
            *column = kUnset;
            for (std::size_t i = 0; i < names.size(); ++i)
                if (lowercase(names[i]) == name) *column = int(i);
            if (*column == kUnset && column != &c.frame)  // "frame" is optional
                throw ParseError(path, line,
                                 std::string("the header has no '") + name +
                                     "' column (expected timestamp, frame, x, y, z, qx, qy, qz, qw)");
        }
        return c;
    }
};

bool sameRow(const OdometryRow& a, const OdometryRow& b) {
    const Vec4f &p = a.quaternion_xyzw, &q = b.quaternion_xyzw;
    return a.timestamp_s == b.timestamp_s && a.frame == b.frame && a.position == b.position && p.x == q.x &&
           p.y == q.y && p.z == q.z && p.w == q.w;
}

}  // namespace

CameraMatrix readCameraMatrix(const std::string& path) {
    text::LineReader in(path, "camera matrix (camera_matrix.csv)");
    std::vector<double> K;
    std::string line;
    int last_line = 1;
    while (in.next(line)) {
        const int line_number = in.lineNumber();
        if (text::isBlankOrComment(line)) continue;
        last_line = line_number;
        const auto tokens = splitCsv(line);
        if (K.size() == 9) throw ParseError(path, line_number, "unexpected content after the 3x3 matrix");
        if (tokens.size() != 3)
            throw ParseError(
                path, line_number,
                "expected 3 numbers (one row of the 3x3 camera matrix), got " + std::to_string(tokens.size()));
        std::vector<double> row;
        std::string bad;
        if (!text::parseDoubles(tokens, row, bad))
            throw ParseError(path, line_number, "not a number: " + text::excerpt(bad));
        for (double v : row)
            if (!text::finiteAsFloat(v))
                throw ParseError(path, line_number, "non-finite value in the camera matrix (stored as floats)");
        K.insert(K.end(), row.begin(), row.end());
    }
    if (K.size() != 9)
        throw ParseError(path, last_line,
                         "expected 3 rows of the 3x3 camera matrix, got " + std::to_string(K.size() / 3));
    if (!(float(K[0]) > 0.f) || !(float(K[4]) > 0.f))
        throw IoError(path, "focal lengths K(0,0) and K(1,1) must be positive");
    if (K[1] != 0.0 || K[3] != 0.0 || K[6] != 0.0 || K[7] != 0.0 || K[8] != 1.0)
        throw IoError(path, "expected K = [fx 0 cx; 0 fy cy; 0 0 1] (no skew)");
    return CameraMatrix{K[0], K[4], K[2], K[5]};
}

std::vector<OdometryRow> readOdometry(const std::string& path) {
    text::LineReader in(path, "odometry (odometry.csv)");
    std::vector<OdometryRow> rows;
    std::map<int, std::pair<std::size_t, int>> line_of_frame;    // frame -> (its row, its line)
    std::map<double, std::pair<std::size_t, int>> line_of_time;  // timestamp -> (its row, its line)
    OdometryColumns columns;
    bool first = true;
    std::string line;
    while (in.next(line)) {
        const int line_number = in.lineNumber();
        if (text::isBlankOrComment(line)) continue;
        const auto tokens = splitCsv(line);
        if (tokens.empty()) throw ParseError(path, line_number, "a line without values");  // found by fuzzing
        double probe = 0.0;
        if (first && !text::parseDouble(tokens.front(), probe)) {
            columns = OdometryColumns::fromHeader(tokens, path, line_number);
            first = false;
            continue;
        }
        first = false;
        if (int(tokens.size()) != columns.count)
            throw ParseError(
                path, line_number,
                "expected " + std::to_string(columns.count) + " values, got " + std::to_string(tokens.size()));
        std::vector<double> v;
        std::string bad;
        if (!text::parseDoubles(tokens, v, bad))
            throw ParseError(path, line_number, "not a number: " + text::excerpt(bad));
        for (std::size_t i = 0; i < v.size(); ++i)
            if (!text::finiteAsFloat(v[i]) && int(i) != columns.timestamp)
                throw ParseError(path, line_number,
                                 "non-finite value " + text::excerpt(tokens[i]) + " (stored as a float)");
        OdometryRow row;
        row.timestamp_s = v[std::size_t(columns.timestamp)];
        if (!std::isfinite(row.timestamp_s))
            throw ParseError(path, line_number,
                             "non-finite timestamp " + text::excerpt(tokens[std::size_t(columns.timestamp)]));
        if (columns.frame == OdometryColumns::kUnset) {
            row.frame = int(rows.size());
        } else {
            const double frame = v[std::size_t(columns.frame)];
            if (frame < 0.0 || frame != std::floor(frame) || frame > 1e9)
                throw ParseError(path, line_number,
                                 "the frame number must be a non-negative integer, got " +
                                     text::excerpt(tokens[std::size_t(columns.frame)]));
            row.frame = int(frame);
        }
        row.position =
            Vec3f{float(v[std::size_t(columns.x)]), float(v[std::size_t(columns.y)]), float(v[std::size_t(columns.z)])};
        const double qx = v[std::size_t(columns.qx)], qy = v[std::size_t(columns.qy)], qz = v[std::size_t(columns.qz)],
                     qw = v[std::size_t(columns.qw)];
        std::string problem = text::positionProblem(row.position.x, row.position.y, row.position.z);
        if (problem.empty()) problem = text::quaternionProblem(qx, qy, qz, qw);
        if (!problem.empty()) throw ParseError(path, line_number, problem);
        const double norm = std::sqrt(qx * qx + qy * qy + qz * qz + qw * qw);
        row.quaternion_xyzw = Vec4f{float(qx / norm), float(qy / norm), float(qz / norm), float(qw / norm)};
        // One frame or one time with two poses: which one is right cannot be known.
        const auto [same_frame, new_frame] = line_of_frame.insert({row.frame, {rows.size(), line_number}});
        const auto [same_time, new_time] = line_of_time.insert({row.timestamp_s, {rows.size(), line_number}});
        if (!new_frame || !new_time) {
            const auto& [earlier, earlier_line] = !new_frame ? same_frame->second : same_time->second;
            if (!sameRow(rows[earlier], row))
                throw ParseError(path, line_number,
                                 (!new_frame ? "frame " + std::to_string(row.frame)
                                             : "timestamp " + std::string(tokens[std::size_t(columns.timestamp)])) +
                                     " is given twice, differently (line " + std::to_string(earlier_line) +
                                     " and this one)");
            continue;
        }
        rows.push_back(row);
    }
    return rows;
}

}  // namespace stray_scanner
}  // namespace voxfuse
