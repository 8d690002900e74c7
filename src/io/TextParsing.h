#pragma once
// Internal helpers for the small text formats in io/ (calib.txt, TUM lists and trajectories, 4x4
// pose files, 3x3 K files). Numbers are parsed with std::from_chars, so a user's locale never turns
// "0.5" into 0 and a token is either entirely a number or an error.

#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace voxfuse {
namespace text {

// Opens a text file for reading. IoError naming the file and why it cannot be read ("is a folder, not
// a file", "no such file", "permission denied"); `what` says what the file was meant to be.
std::ifstream openTextFile(const std::string& path, const std::string& what);

// Reads a text file line by line with 1-based line numbers. A line longer than kMaxLineBytes is a
// ParseError (a binary file, or /dev/zero, would otherwise grow one line without bound); a read
// error is an IoError.
class LineReader {
public:
    static constexpr std::size_t kMaxLineBytes = std::size_t(1) << 16;
    LineReader(const std::string& path, const std::string& what);
    // The next line (without its '\n'); false at the end of the file.
    bool next(std::string& line);
    int lineNumber() const { return line_number_; }
    const std::string& path() const { return path_; }

private:
    std::string path_;
    std::ifstream in_;
    int line_number_ = 0;
};

// A whole text file of at most `max_bytes` (IoError beyond: not the small settings file expected).
std::string readSmallTextFile(const std::string& path, const std::string& what,
                              std::size_t max_bytes = std::size_t(1) << 20);

// Splits on spaces, tabs and '\r' (files written on Windows).
std::vector<std::string_view> splitWhitespace(std::string_view line);

// True for lines holding only whitespace, or whose first non-blank character is '#'.
bool isBlankOrComment(std::string_view line);

// Strict conversions: the whole token must be the number. parseDouble accepts a leading '+' and
// also "inf"/"nan"; callers that need finite values check std::isfinite.
bool parseDouble(std::string_view token, double& value);
bool parseInt(std::string_view token, int& value);

// True when `value` is finite as a float, the type the engines compute in: 1e39 is finite as a
// double but not as a float.
bool finiteAsFloat(double value);

// "" for a quaternion that names a rotation once normalised, else why it does not: a value that is
// not finite as a float, or a zero length.
std::string quaternionProblem(double x, double y, double z, double w);

// Camera positions further than this from the origin are no camera's (and their voxel coordinates
// would not fit the engines' ints): 1000 km.
constexpr double kMaxPositionM = 1e6;
// "" for a position within kMaxPositionM of the origin on every axis, else why not.
std::string positionProblem(double x, double y, double z);

// "" when the 3x3 matrix (row-major, 9 values) is a rotation (R R^T = I and det R = +1, within 1e-2),
// else why it is not one.
std::string rotationProblem(const double* R);

// `text` quoted for an error message: control and non-ASCII bytes as \xNN (a file cannot send escape
// sequences to the user's terminal), cut after 80 characters.
std::string excerpt(std::string_view text);

// "" when a 4x4 pose (row-major, 16 values) is rigid: a rotation, a plausible position, last row
// 0 0 0 1; else why not.
std::string rigidPoseProblem(const float* T);

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
