#pragma once
// Internal helpers for the small text formats in io/ (calib.txt, TUM lists and trajectories, 4x4
// pose files, 3x3 K files). Numbers are parsed with std::from_chars, so a user's locale never turns
// "0.5" into 0 and a token is either entirely a number or an error.

#include <string>
#include <string_view>
#include <vector>

namespace voxfuse {
namespace text {

// Splits on spaces, tabs and '\r' (files written on Windows).
std::vector<std::string_view> splitWhitespace(std::string_view line);

// True for lines holding only whitespace, or whose first non-blank character is '#'.
bool isBlankOrComment(std::string_view line);

// Strict conversions: the whole token must be the number. parseDouble accepts a leading '+' and
// also "inf"/"nan"; callers that need finite values check std::isfinite.
bool parseDouble(std::string_view token, double& value);
bool parseInt(std::string_view token, int& value);

// Parses every token of `tokens` as a double; on failure returns false and sets `bad` to the token.
bool parseDoubles(const std::vector<std::string_view>& tokens, std::vector<double>& values, std::string& bad);

// The shortest text that reads back as exactly `value` ("504.261", not "504.260986").
std::string formatFloat(float value);

// Reads a text file holding exactly rows x cols whitespace-separated numbers, one matrix row per
// line ('#' and blank lines skipped). Row-major result; values may be non-finite (the caller
// decides). Throws IoError if the file cannot be opened, ParseError naming the line otherwise.
std::vector<double> readNumberMatrix(const std::string& path, int rows, int cols);

}  // namespace text
}  // namespace voxfuse
