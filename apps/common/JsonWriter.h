#pragma once
// A minimal streaming JSON writer for flat reports (objects, arrays, numbers, strings).

#include <cmath>
#include <ostream>
#include <string>
#include <vector>

namespace voxfuse::app {

class JsonWriter {
public:
    explicit JsonWriter(std::ostream& out) : out_(out) { out_.precision(10); }

    JsonWriter& beginObject(const char* key = nullptr) { return open(key, '{'); }
    JsonWriter& endObject() { return close('}'); }
    JsonWriter& beginArray(const char* key = nullptr) { return open(key, '['); }
    JsonWriter& endArray() { return close(']'); }

    JsonWriter& value(const char* key, double v) {
        prefix(key);
        if (std::isfinite(v)) out_ << v; else out_ << "null";
        return *this;
    }
    JsonWriter& value(const char* key, long long v) { prefix(key); out_ << v; return *this; }
    JsonWriter& value(const char* key, int v) { return value(key, (long long)v); }
    JsonWriter& value(const char* key, bool v) { prefix(key); out_ << (v ? "true" : "false"); return *this; }
    JsonWriter& value(const char* key, const std::string& v) { prefix(key); quoted(v); return *this; }
    JsonWriter& value(const char* key, const char* v) { return value(key, std::string(v)); }

private:
    JsonWriter& open(const char* key, char bracket) {
        prefix(key);
        out_ << bracket;
        first_.push_back(true);
        return *this;
    }
    JsonWriter& close(char bracket) {
        first_.pop_back();
        out_ << '\n' << std::string(2 * first_.size(), ' ') << bracket;
        if (first_.empty()) out_ << '\n';
        return *this;
    }
    void prefix(const char* key) {
        if (!first_.empty()) {
            if (!first_.back()) out_ << ',';
            first_.back() = false;
            out_ << '\n' << std::string(2 * first_.size(), ' ');
        }
        if (key) {
            quoted(key);
            out_ << ": ";
        }
    }
    void quoted(const std::string& s) {
        out_ << '"';
        for (char c : s) {
            if (c == '"' || c == '\\') out_ << '\\' << c;
            else if (c == '\n') out_ << "\\n";
            else if (static_cast<unsigned char>(c) < 0x20) out_ << ' ';
            else out_ << c;
        }
        out_ << '"';
    }

    std::ostream& out_;
    std::vector<bool> first_;
};

}  // namespace voxfuse::app
