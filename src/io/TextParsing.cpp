#include "TextParsing.h"

#include <charconv>
#include <fstream>

#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace text {

namespace {
bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }
}  // namespace

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

std::string formatFloat(float value) {
    char buffer[64];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
    return std::string(buffer, result.ptr);
}

std::vector<double> readNumberMatrix(const std::string& path, int rows, int cols) {
    std::ifstream in(path);
    if (!in) throw IoError(path, "cannot open file");
    const std::string shape = std::to_string(rows) + "x" + std::to_string(cols) + " matrix";
    std::vector<double> matrix;
    std::string line;
    int line_number = 0;
    int rows_read = 0;
    while (std::getline(in, line)) {
        ++line_number;
        if (isBlankOrComment(line)) continue;
        if (rows_read == rows)
            throw ParseError(path, line_number, "unexpected content after the " + shape + ": '" + line + "'");
        const auto tokens = splitWhitespace(line);
        if (int(tokens.size()) != cols)
            throw ParseError(path, line_number, "expected " + std::to_string(cols) + " numbers in row " +
                                                    std::to_string(rows_read + 1) + " of a " + shape + ", got " +
                                                    std::to_string(tokens.size()));
        std::vector<double> values;
        std::string bad;
        if (!parseDoubles(tokens, values, bad)) throw ParseError(path, line_number, "not a number: '" + bad + "'");
        matrix.insert(matrix.end(), values.begin(), values.end());
        ++rows_read;
    }
    if (rows_read < rows)
        throw ParseError(path, line_number > 0 ? line_number : 1,
                         "unexpected end of file: expected a " + shape + ", got " + std::to_string(rows_read) +
                             " row(s)");
    return matrix;
}

}  // namespace text
}  // namespace voxfuse
