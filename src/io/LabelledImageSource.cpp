#include "voxfuse/io/LabelledImageSource.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

#include "../core/NearestInTime.h"
#include "FrameReading.h"
#include "TextParsing.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/ImageIO.h"

namespace voxfuse {

namespace fs = std::filesystem;

namespace {

std::string lowerExtension(const fs::path& p) {
    std::string ext = p.extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

// Lossless formats only: JPEG compression would turn class ids into their neighbours' values.
bool isLabelImageName(const fs::path& p) {
    const std::string ext = lowerExtension(p);
    return ext == ".png" || ext == ".pgm" || ext == ".tif" || ext == ".tiff";
}

bool isJpegName(const fs::path& p) {
    const std::string ext = lowerExtension(p);
    return ext == ".jpg" || ext == ".jpeg";
}

bool isDigit(char c) { return c >= '0' && c <= '9'; }

// Digits with at most one '.' ("1305031102.175304", "17"): a time in seconds. Stricter than
// text::parseDouble, which would also take "1e3", "inf" or "-2".
bool parseDecimalName(const std::string& stem, double& value, bool& has_point) {
    int digits = 0, points = 0;
    for (char c : stem) {
        if (isDigit(c))
            ++digits;
        else if (c == '.')
            ++points;
        else
            return false;
    }
    has_point = points == 1;
    return digits > 0 && points <= 1 && text::parseDouble(stem, value) && std::isfinite(value);
}

// "frame2" before "frame10": runs of digits compare by value, everything else by character. Names
// equal in that order ("07" and "7") fall back to plain comparison so that the order is total.
bool naturalLess(const std::string& a, const std::string& b) {
    std::size_t i = 0, j = 0;
    while (i < a.size() && j < b.size()) {
        if (isDigit(a[i]) && isDigit(b[j])) {
            std::size_t ei = i, ej = j;
            while (ei < a.size() && isDigit(a[ei])) ++ei;
            while (ej < b.size() && isDigit(b[ej])) ++ej;
            std::size_t si = i, sj = j;  // skip leading zeros
            while (si + 1 < ei && a[si] == '0') ++si;
            while (sj + 1 < ej && b[sj] == '0') ++sj;
            if (ei - si != ej - sj) return ei - si < ej - sj;
            const int c = a.compare(si, ei - si, b, sj, ej - sj);
            if (c != 0) return c < 0;
            i = ei;
            j = ej;
        } else {
            if (a[i] != b[j]) return static_cast<unsigned char>(a[i]) < static_cast<unsigned char>(b[j]);
            ++i;
            ++j;
        }
    }
    if ((i < a.size()) != (j < b.size())) return i >= a.size();  // a prefix sorts first
    return a < b;
}

const char* matchName(LabelStreamOptions::Match match) {
    return match == LabelStreamOptions::Match::Timestamp ? "timestamp" : "frame index";
}

// The frame number in a label image's name: its last run of digits ("frame-000042" -> 42). Names
// with a '.' (timestamps like "1305031102.175304") have none.
bool lastNumber(const std::string& stem, long long& number) {
    if (stem.find('.') != std::string::npos) return false;
    std::size_t end = stem.size();
    while (end > 0 && !isDigit(stem[end - 1])) --end;
    std::size_t begin = end;
    while (begin > 0 && isDigit(stem[begin - 1])) --begin;
    if (begin == end || end - begin > 15) return false;  // none, or too long for a frame number
    number = std::stoll(stem.substr(begin, end - begin));
    return true;
}

// The numbers of the (sorted) images' names, when every name has one, they increase strictly in that
// order, and they are dense enough to be frame numbers (spanning at most 4 per image plus 1000, not
// e.g. nanosecond timestamps).
bool frameNumbers(const std::vector<std::string>& stems, std::vector<long long>& numbers) {
    numbers.clear();
    for (const std::string& stem : stems) {
        long long n = 0;
        if (!lastNumber(stem, n) || (!numbers.empty() && n <= numbers.back())) return false;
        numbers.push_back(n);
    }
    return !numbers.empty() && numbers.back() - numbers.front() <= 4 * (long long)numbers.size() + 1000;
}

}  // namespace

LabelledImageSource::LabelledImageSource(std::unique_ptr<ImageSource> source, const LabelStreamOptions& options)
    : source_(std::move(source)), options_(options) {
    if (!source_) throw ConfigError("labelled source: no image source to attach labels to");
    if (options_.path.empty()) throw ConfigError("labels: no label folder or list file given");
    if (!std::isfinite(options_.max_time_difference_s) || options_.max_time_difference_s < 0.0)
        throw ConfigError("labels: the maximum time difference must be finite and >= 0, got " +
                          std::to_string(options_.max_time_difference_s) + " s");
    if (options_.ignore_id < -1 || options_.ignore_id > 65535)
        throw ConfigError("labels: ignore id " + std::to_string(options_.ignore_id) +
                          " out of range: expected -1 (none) or 0..65535");

    std::error_code ec;
    if (fs::is_directory(options_.path, ec)) {
        readFolder();
    } else if (fs::is_regular_file(options_.path, ec)) {
        if (isLabelImageName(options_.path) || isJpegName(options_.path))
            throw IoError(options_.path,
                          "this is an image; labels need a folder of label images or a list file of them");
        is_list_ = true;
        readList();
    } else {
        throw IoError(options_.path, "no such label folder or list file");
    }
}

void LabelledImageSource::readFolder() {
    const std::string& folder = options_.path;
    struct Found {
        std::string path, stem;
        double time_s;
        bool decimal, has_point;
    };
    std::vector<Found> found;
    int jpegs = 0;
    std::error_code ec;
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
        const fs::path& p = it->path();
        const std::string name = p.filename().string();
        std::error_code type_ec;
        if (name.empty() || name[0] == '.' || !it->is_regular_file(type_ec)) continue;  // hidden files, folders
        if (isJpegName(p)) ++jpegs;
        if (!isLabelImageName(p)) continue;
        Found f{p.string(), p.stem().string(), 0.0, false, false};
        f.decimal = parseDecimalName(f.stem, f.time_s, f.has_point);
        found.push_back(std::move(f));
    }
    if (ec) throw IoError(folder, "cannot list the label folder: " + ec.message());
    if (found.empty())
        throw IoError(folder, "no label images (.png, .pgm, .tif, .tiff) in this folder" +
                                  (jpegs > 0 ? "; its " + std::to_string(jpegs) +
                                                   " JPEG files cannot hold class ids (lossy compression changes them)"
                                             : std::string()));

    const bool all_decimal = std::all_of(found.begin(), found.end(), [](const Found& f) { return f.decimal; });
    const bool all_timestamps =
        all_decimal && std::all_of(found.begin(), found.end(), [](const Found& f) { return f.has_point; });
    match_ = options_.match != LabelStreamOptions::Match::Automatic
                 ? options_.match
                 : (all_timestamps ? LabelStreamOptions::Match::Timestamp : LabelStreamOptions::Match::Index);

    if (match_ == LabelStreamOptions::Match::Timestamp) {
        const auto bad = std::find_if(found.begin(), found.end(), [](const Found& f) { return !f.decimal; });
        if (bad != found.end())
            throw IoError(folder,
                          "timestamp matching needs label files named by their time in seconds (e.g. "
                          "1305031102.175304.png); '" +
                              fs::path(bad->path).filename().string() + "' is not");
        std::sort(found.begin(), found.end(), [](const Found& a, const Found& b) {
            return a.time_s != b.time_s ? a.time_s < b.time_s : a.path < b.path;
        });
    } else if (all_decimal) {
        // Natural order would compare "1.5" and "1.25" digit run by digit run; by value is what is meant.
        std::sort(found.begin(), found.end(), [](const Found& a, const Found& b) {
            return a.time_s != b.time_s ? a.time_s < b.time_s : naturalLess(a.stem, b.stem);
        });
    } else {
        std::sort(found.begin(), found.end(), [](const Found& a, const Found& b) {
            return a.stem != b.stem ? naturalLess(a.stem, b.stem) : a.path < b.path;
        });
    }
    image_count_ = int(found.size());
    std::vector<long long> numbers;
    std::vector<std::string> stems;
    for (const Found& f : found) stems.push_back(f.stem);
    if (match_ == LabelStreamOptions::Match::Index && frameNumbers(stems, numbers)) {
        images_.resize(std::size_t(numbers.back() - numbers.front() + 1));
        first_number_ = numbers.front();
        for (std::size_t i = 0; i < found.size(); ++i)
            images_[std::size_t(numbers[i] - numbers.front())] = {found[i].time_s, std::move(found[i].path)};
        return;
    }
    images_.reserve(found.size());
    for (Found& f : found) images_.push_back({f.time_s, std::move(f.path)});
}

void LabelledImageSource::readList() {
    const std::string& path = options_.path;
    match_ =
        options_.match == LabelStreamOptions::Match::Automatic ? LabelStreamOptions::Match::Timestamp : options_.match;
    for (frame_reading::ListedImage& listed : frame_reading::readTimestampedImageList(path, missing_listed_files_)) {
        // By index a missing file keeps its line's place, so that the frames after it keep theirs.
        if (listed.on_disk)
            images_.push_back({listed.time_s, std::move(listed.path)});
        else if (match_ == LabelStreamOptions::Match::Index)
            images_.push_back({listed.time_s, std::string()});
        image_count_ += listed.on_disk;
    }
    if (image_count_ == 0)
        throw IoError(path, missing_listed_files_ > 0 ? "none of the " + std::to_string(missing_listed_files_) +
                                                            " listed label images is on disk"
                                                      : std::string("the label list names no images"));
    if (match_ == LabelStreamOptions::Match::Timestamp)
        std::stable_sort(images_.begin(), images_.end(),
                         [](const LabelImage& a, const LabelImage& b) { return a.time_s < b.time_s; });
}

const LabelledImageSource::LabelImage* LabelledImageSource::find(const RGBDFrame& frame) const {
    if (match_ == LabelStreamOptions::Match::Index) {
        // Numbered labels meet frames numbered by their files by number: frame-000017 takes 17, however
        // the numbers skip. Otherwise the frame's place in the source is the image's place.
        const long long at =
            first_number_ >= 0 && frame.file_number >= 0 ? frame.file_number - first_number_ : frame.index;
        if (at < 0 || std::size_t(at) >= images_.size()) return nullptr;
        const LabelImage& image = images_[std::size_t(at)];
        return image.path.empty() ? nullptr : &image;
    }
    const double t = frame.rgb_timestamp_s >= 0.0 ? frame.rgb_timestamp_s : frame.timestamp_s;
    return nearestInTime(images_, t, options_.max_time_difference_s,
                         [](const LabelImage& image) { return image.time_s; });
}

bool LabelledImageSource::next(RGBDFrame& frame) {
    if (!source_->next(frame)) return false;
    // Callers reuse frames and the source does not touch labels: never leave the previous frame's.
    frame.labels = Image<ClassId>();
    frame.labels_path.clear();
    const LabelImage* image = find(frame);
    if (!image) {
        ++without_labels_;
        return true;
    }
    Image<ClassId> labels;
    try {
        labels = readLabelImage(image->path, options_.ignore_id);
    } catch (const IoError& e) {
        ++label_errors_;
        throw IoError(e.file(), e.reason(), frame.index);
    }
    // Checked here too, not only by the engine: here the frame is skipped, there the run would stop.
    try {
        checkLabelImageSize(labels.size(), source_->calib(), image->path, frame.index);
    } catch (const IoError&) {
        ++label_errors_;
        throw;
    }
    frame.labels = std::move(labels);
    frame.labels_path = image->path;
    ++with_labels_;
    return true;
}

std::string LabelledImageSource::description() const {
    std::string d = source_->description() + " + labels from " + options_.path + " (" + std::to_string(image_count_) +
                    (is_list_ ? " listed" : "") + " label images, matched by " + matchName(match_);
    if (match_ == LabelStreamOptions::Match::Index && int(images_.size()) > image_count_)
        d += ", " + std::to_string(int(images_.size()) - image_count_) + " frames in between without one";
    if (match_ == LabelStreamOptions::Match::Timestamp)
        d += " within " + text::formatFloat(float(options_.max_time_difference_s)) + " s";
    if (options_.ignore_id >= 0) d += "; class " + std::to_string(options_.ignore_id) + " = no label";
    if (missing_listed_files_ > 0) d += "; " + std::to_string(missing_listed_files_) + " listed images not on disk";
    return d + ")";
}

}  // namespace voxfuse
