#pragma once
// Exceptions for bad input and failed device calls. Every message names what failed and where
// (file, line or frame) so that a user can act on it.

#include <stdexcept>
#include <string>

namespace voxfuse {

class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// A file could not be read or holds something we cannot use. `frame` < 0 means "not a frame".
class IoError : public Error {
public:
    IoError(const std::string& file, const std::string& reason, int frame = -1)
        : IoError(file, file + (frame >= 0 ? ": frame " + std::to_string(frame) : std::string()) + ": " + reason,
                  reason, frame) {}
    const std::string& file() const { return file_; }
    int frame() const { return frame_; }
    const std::string& reason() const { return reason_; }

protected:
    // For subclasses that place the location differently in the message.
    IoError(const std::string& file, const std::string& message, const std::string& reason, int frame)
        : Error(message), file_(file), frame_(frame), reason_(reason) {}

private:
    std::string file_;
    int frame_;
    std::string reason_;
};

// A text file has a malformed line (1-based line number). what() reads "file:line: reason"; file()
// is the bare path.
class ParseError : public IoError {
public:
    ParseError(const std::string& file, int line, const std::string& reason)
        : IoError(file, file + ":" + std::to_string(line) + ": " + reason, reason, -1), line_(line) {}
    int line() const { return line_; }

private:
    int line_;
};

// A setting is out of range or inconsistent.
class ConfigError : public Error {
public:
    using Error::Error;
};

// A CUDA runtime call failed, or CUDA was asked for in a build or on a machine without it.
class DeviceError : public Error {
public:
    using Error::Error;
};

}  // namespace voxfuse
