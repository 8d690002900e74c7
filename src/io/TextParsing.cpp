#include "TextParsing.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <sstream>

#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace text {

namespace {
bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }
std::string readFailureReason(int error_number) {
    switch (error_number) {
        case ENOENT:
            return "no such file";
        case EACCES:
        case EPERM:
            return "permission denied";
        case EISDIR:
            return "is a folder, not a file";
        default:
            return error_number != 0 ? std::strerror(error_number) : "cannot open";
    }
}

std::string formatDouble(double v) {
    std::ostringstream out;
    out << v;
    return out.str();
}

}  // namespace

std::ifstream openTextFile(const std::string& path, const std::string& what) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
        throw IoError(path, "is a folder, not a file (expected the " + what + ")");
    errno = 0;
    std::ifstream in(path);
    if (!in) throw IoError(path, "cannot open the " + what + ": " + readFailureReason(errno));
    return in;
}

LineReader::LineReader(const std::string& path, const std::string& what) : path_(path), in_(openTextFile(path, what)) {}

bool LineReader::next(std::string& line) {
    line.clear();
    std::streambuf* buffer = in_.rdbuf();
    bool any = false;
    for (;;) {
        const int c = buffer->sbumpc();
        if (c == std::char_traits<char>::eof()) break;
        any = true;
        if (c == '\n') break;
        if (line.size() == kMaxLineBytes)
            throw ParseError(
                path_, line_number_ + 1,
                "line longer than " + std::to_string(kMaxLineBytes) + " bytes: not a text file of this kind");
        line.push_back(char(c));
    }
    if (!any) return false;
    ++line_number_;
    return true;
}

std::string readSmallTextFile(const std::string& path, const std::string& what, std::size_t max_bytes) {
    std::ifstream in = openTextFile(path, what);
    std::string text;
    std::streambuf* buffer = in.rdbuf();
    for (int c = buffer->sbumpc(); c != std::char_traits<char>::eof(); c = buffer->sbumpc()) {
        if (text.size() == max_bytes)
            throw IoError(path, "larger than " + std::to_string(max_bytes) + " bytes: not a " + what);
        text.push_back(char(c));
    }
    return text;
}

std::vector<std::string_view> splitWhitespace(std::string_view line) {
    std::vector<std::string_view> tokens;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && isSpace(line[i])) ++i;
        const std::size_t start = i;
        while (i < line.size() && !isSpace(line[i])) ++i;
        if (i > start) tokens.push_back(line.substr(start, i - start));
    }
    return tokens;
}

bool isBlankOrComment(std::string_view line) {
    for (char c : line) {
        if (isSpace(c)) continue;
        return c == '#';
    }
    return true;
}

bool parseDouble(std::string_view token, double& value) {
    if (!token.empty() && token.front() == '+') token.remove_prefix(1);
    if (token.empty()) return false;
    const char* end = token.data() + token.size();
    const auto result = std::from_chars(token.data(), end, value);
    return result.ec == std::errc() && result.ptr == end;
}

bool parseInt(std::string_view token, int& value) {
    if (!token.empty() && token.front() == '+') token.remove_prefix(1);
    if (token.empty()) return false;
    const char* end = token.data() + token.size();
    const auto result = std::from_chars(token.data(), end, value);
    return result.ec == std::errc() && result.ptr == end;
}

bool parseDoubles(const std::vector<std::string_view>& tokens, std::vector<double>& values, std::string& bad) {
    values.resize(tokens.size());
    for (std::size_t i = 0; i < tokens.size(); ++i) {
        if (!parseDouble(tokens[i], values[i])) {
            bad = std::string(tokens[i]);
            return false;
        }
    }
    return true;
}

std::string excerpt(std::string_view text) {
    constexpr std::size_t kMaxShown = 80;
    std::string out = "'";
    for (std::size_t i = 0; i < text.size() && i < kMaxShown; ++i) {
        const unsigned char c = static_cast<unsigned char>(text[i]);
        if (c >= 0x20 && c < 0x7f) {
            out += char(c);
        } else {
            static const char* hex = "0123456789abcdef";
            out += "\\x";
            out += hex[c >> 4];
            out += hex[c & 15];
        }
    }
    out += text.size() > kMaxShown ? "'..." : "'";
    return out;
}

bool finiteAsFloat(double value) {
    return std::isfinite(value) && std::abs(value) <= double(std::numeric_limits<float>::max());
}

std::string quaternionProblem(double x, double y, double z, double w) {
    for (double v : {x, y, z, w})
        if (!finiteAsFloat(v)) return "non-finite quaternion (stored as floats)";
    if (std::sqrt(x * x + y * y + z * z + w * w) < 1e-6) return "zero-length quaternion: not a rotation";
    return {};
}

std::string rotationProblem(const double* R) {
    double worst = 0.0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double dot = 0.0;
            for (int k = 0; k < 3; ++k) dot += R[3 * i + k] * R[3 * j + k];
            worst = std::max(worst, std::abs(dot - (i == j ? 1.0 : 0.0)));
        }
    if (!(worst <= 1e-2)) return "not a rotation (R R^T differs from the identity by " + formatDouble(worst) + ")";
    const double det =
        R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) + R[2] * (R[3] * R[7] - R[4] * R[6]);
    if (det < 0.0) return "not a rotation (a reflection: its determinant is " + formatDouble(det) + ")";
    return {};
}

std::string positionProblem(double x, double y, double z) {
    for (double v : {x, y, z})
        if (!(std::abs(v) <= kMaxPositionM))
            return "position " + formatDouble(v) + " m is further than " + formatDouble(kMaxPositionM) +
                   " m from the origin";
    return {};
}

std::string rigidPoseProblem(const float* T) {
    if (T[12] != 0.f || T[13] != 0.f || T[14] != 0.f || T[15] != 1.f) return "the last row of the pose is not 0 0 0 1";
    const double R[9] = {T[0], T[1], T[2], T[4], T[5], T[6], T[8], T[9], T[10]};
    const std::string rotation = rotationProblem(R);
    if (!rotation.empty()) return "the pose's rotation is " + rotation;
    return positionProblem(T[3], T[7], T[11]);
}

std::string formatFloat(float value) {
    char buffer[64];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
    return std::string(buffer, result.ptr);
}

std::vector<double> readNumberMatrix(const std::string& path, int rows, int cols) {
    const std::string shape = std::to_string(rows) + "x" + std::to_string(cols) + " matrix";
    LineReader in(path, shape + " file");
    std::vector<double> matrix;
    std::string line;
    int rows_read = 0;
    while (in.next(line)) {
        const int line_number = in.lineNumber();
        if (isBlankOrComment(line)) continue;
        if (rows_read == rows)
            throw ParseError(path, line_number, "unexpected content after the " + shape + ": " + excerpt(line));
        const auto tokens = splitWhitespace(line);
        if (int(tokens.size()) != cols)
            throw ParseError(path, line_number,
                             "expected " + std::to_string(cols) + " numbers in row " + std::to_string(rows_read + 1) +
                                 " of a " + shape + ", got " + std::to_string(tokens.size()));
        std::vector<double> values;
        std::string bad;
        if (!parseDoubles(tokens, values, bad)) throw ParseError(path, line_number, "not a number: " + excerpt(bad));
        matrix.insert(matrix.end(), values.begin(), values.end());
        ++rows_read;
    }
    if (rows_read < rows)
        throw ParseError(
            path, std::max(in.lineNumber(), 1),
            "unexpected end of file: expected a " + shape + ", got " + std::to_string(rows_read) + " row(s)");
    return matrix;
}

}  // namespace text
}  // namespace voxfuse
