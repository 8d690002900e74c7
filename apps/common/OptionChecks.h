#pragma once
// Checks of command-line numbers in the type they are used in, for CLI11 options: a float option
// must be a number that is finite as a float (1e39 is finite as a double, infinite as a float) and
// in its range; NaN is never in a range. CLI11's own PositiveNumber and Range let NaN through and
// print their bounds as 300-digit numbers. File names whose form can be checked up front are too.

#include <CLI/CLI.hpp>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <system_error>

#include "voxfuse/io/MeshIO.h"

namespace voxfuse::app {

namespace option_checks {

inline bool parseNumber(std::string text, double& value) {
    if (!text.empty() && text.front() == '+') text.erase(0, 1);
    const char* end = text.data() + text.size();
    const auto result = std::from_chars(text.data(), end, value);
    return !text.empty() && result.ec == std::errc() && result.ptr == end;
}

inline std::string bound(double v) {
    std::ostringstream out;
    out << v;
    return out.str();
}

}  // namespace option_checks

// A float in [lo, hi], or (lo, hi] with lo_open (hi may be infinity: no upper bound).
inline CLI::Validator floatIn(double lo, double hi, bool lo_open = false) {
    const std::string range = (lo_open ? "(" : "[") + option_checks::bound(lo) + ", " +
                              (std::isinf(hi) ? std::string("inf)") : option_checks::bound(hi) + "]");
    return CLI::Validator(
        [=](std::string& text) -> std::string {
            double v = 0.0;
            if (!option_checks::parseNumber(text, v)) return "'" + text + "' is not a number";
            if (!std::isfinite(v) || std::abs(v) > double(std::numeric_limits<float>::max()))
                return "'" + text + "' is not a finite number (values are stored as floats)";
            const double as_float = double(float(v));
            if (!(lo_open ? as_float > lo : as_float >= lo) || !(as_float <= hi))
                return "'" + text + "' is not in " + range;
            return {};
        },
        "FLOAT in " + range);
}

inline CLI::Validator positiveFloat() { return floatIn(0.0, std::numeric_limits<double>::infinity(), true); }
inline CLI::Validator nonNegativeFloat() { return floatIn(0.0, std::numeric_limits<double>::infinity()); }

// An integer in [lo, hi].
inline CLI::Validator intIn(long long lo, long long hi) {
    const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    return CLI::Validator(
        [=](std::string& text) -> std::string {
            std::string digits = text;
            if (!digits.empty() && digits.front() == '+') digits.erase(0, 1);
            long long v = 0;
            const char* end = digits.data() + digits.size();
            const auto result = std::from_chars(digits.data(), end, v);
            if (digits.empty() || result.ptr != end || result.ec == std::errc::invalid_argument)
                return "'" + text + "' is not an integer";
            if (result.ec == std::errc::result_out_of_range || v < lo || v > hi)
                return "'" + text + "' is not in " + range;
            return {};
        },
        "INT in " + range);
}

inline CLI::Validator positiveInt() { return intIn(1, std::numeric_limits<int>::max()); }
inline CLI::Validator nonNegativeInt() { return intIn(0, std::numeric_limits<int>::max()); }

// A mesh file to write: a name whose extension is a mesh format the writer knows, not a folder.
// Checked while the command line is read, before a run that would only fail at its end.
inline CLI::Validator meshFileName() {
    return CLI::Validator(
        [](std::string& path) -> std::string {
            std::error_code ec;
            if (std::filesystem::is_directory(path, ec)) return "'" + path + "' is a folder, not a file";
            if (!isMeshFileName(path))
                return "'" + path + "': unknown mesh format '" + std::filesystem::path(path).extension().string() +
                       "' (expected .ply, .obj or .stl)";
            return {};
        },
        "MESH FILE");
}

// A former spelling of an option, kept for a release: hidden from --help, it sets the same value
// (with the same checks, given by the caller) and says on stderr which name to use.
template <class T>
CLI::Option* addFormerSpelling(CLI::App& cli, const std::string& former, CLI::Option* current, T& value) {
    CLI::Option* o = cli.add_option(former, value)->group("");
    const std::string now = current->get_name();
    o->each([former, now](const std::string&) {
        std::cerr << "warning: " << former << " is the former spelling of " << now << ", which it will give way to\n";
    });
    return o;  // given with the current name too, the last one on the command line counts
}

}  // namespace voxfuse::app
