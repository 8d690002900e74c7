#pragma once
// Semantic labels for the frames of any other source: a folder of label images, or a TUM-style list of
// them, matched to the frames by index or by timestamp and attached as RGBDFrame::labels. Label images
// hold one class id per pixel (io/ImageIO.h readLabelImage) and are usually a segmentation network's
// output for the colour images, so they must show the colour camera's field of view, at any resolution.

#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "voxfuse/io/ImageSource.h"

namespace voxfuse {

struct LabelStreamOptions {
    // A folder of label images (.png, .pgm, .tif, .tiff; other files are ignored), or a list file in
    // the layout of TUM's rgb.txt: '#' comments, one "timestamp path" line per image, paths relative to
    // the list file's folder (or absolute). Listed images missing on disk are skipped and counted.
    std::string path;

    enum class Match {
        // Timestamp for a list file, or for a folder whose file names are all decimal numbers with a
        // '.' (TUM style, "1305031102.175304.png"); Index otherwise.
        Automatic,
        // The k-th label image belongs to the frame with RGBDFrame::index k (sources number frames from
        // 0 in reading order). A list file's k-th line is the k-th image, also when that file is missing
        // (then frame k has no labels). A folder whose names all carry a number (its last digit run:
        // "000042.png", "frame-42.png") matches it to the number in the frame's own file names where
        // the source has them (RGBDFrame::file_number: frame folders, Stray Scanner captures, whose
        // numbers may skip), else places each image by its number minus the smallest, as the frame
        // index; either way a gap in the numbers is a frame without labels. Other folders (or numbers
        // so sparse that they cannot be frame numbers) take their images in natural order of their
        // names ("2.png" before "10.png"). Frames past the last image get no labels.
        Index,
        // A frame takes the label image whose timestamp (the list's first column, or the file name as a
        // number of seconds) is nearest to the frame's colour image (RGBDFrame::rgb_timestamp_s where
        // the source sets it, else timestamp_s), if within max_time_difference_s; otherwise it has no
        // labels. A label image may serve more than one frame.
        Timestamp
    };
    Match match = Match::Automatic;

    // Timestamp matching only. Labels are computed from (and stamped like) the colour images, whose
    // time TUM sources pass on: 0.02 s (as TUM's own pairing) leaves room for labels stamped with
    // rounded times, or with the depth image's time. Must be finite and >= 0.
    double max_time_difference_s = 0.02;

    // Class id that means "no label" in the files (often 0 = unlabelled/background, or 255 for 8-bit
    // masks); those pixels become kNoLabel. -1: none ignored. 65535 is always kNoLabel. Range -1..65535.
    int ignore_id = 0;
};

class LabelledImageSource : public ImageSource {
public:
    // Takes `source` over. Reads the folder or list and chooses the matching (no image is decoded yet).
    // Throws ConfigError for an empty path, a null source or out-of-range options; IoError/ParseError
    // naming the path and the reason for a missing path, a malformed list, no label images, or
    // timestamp matching asked of a folder whose file names are not numbers.
    LabelledImageSource(std::unique_ptr<ImageSource> source, const LabelStreamOptions& options);

    const RGBDCalib& calib() const override { return source_->calib(); }
    // The source's next frame with labels/labels_path set when a label image matches it (cleared
    // otherwise). A frame the source cannot read throws as the source does. A label image that cannot
    // be read, is not a class-id image, or does not have the colour camera's aspect ratio (within 1%;
    // calib().rgb, or calib().depth when rgb is invalid) throws IoError naming the label file, the
    // frame and the reason; the frame is skipped and the next call moves on.
    bool next(RGBDFrame& frame) override;
    int frameCount() const override { return source_->frameCount(); }
    // The source's description + " + labels from PATH (N images, matched by ...)".
    std::string description() const override;
    const std::vector<TimedPose>& groundTruth() const override { return source_->groundTruth(); }
    bool isLive() const override { return source_->isLive(); }

    // The matching in use (never Automatic) and the number of label images found on disk.
    LabelStreamOptions::Match match() const { return match_; }
    int labelImageCount() const { return image_count_; }
    int missingListedFiles() const { return missing_listed_files_; }  // listed, but not on disk

    // Frames delivered so far with labels, without (no label image matched), and frames skipped because
    // their label image threw. Safe to read from another thread.
    long framesWithLabels() const { return with_labels_; }
    long framesWithoutLabels() const { return without_labels_; }
    long labelErrors() const { return label_errors_; }

private:
    struct LabelImage {
        double time_s;     // Timestamp matching only
        std::string path;  // Index matching: "" for a frame without a label image (a gap)
    };

    void readFolder();
    void readList();
    const LabelImage* find(const RGBDFrame& frame) const;

    std::unique_ptr<ImageSource> source_;
    LabelStreamOptions options_;
    LabelStreamOptions::Match match_ = LabelStreamOptions::Match::Index;
    bool is_list_ = false;
    std::vector<LabelImage>
        images_;  // Index: one per frame index, from 0 (or per number, from first_number_); Timestamp: sorted by time
    long long first_number_ = -1;  // Index, a numbered folder: the smallest label number; -1 otherwise
    int image_count_ = 0;          // entries of images_ with a file
    int missing_listed_files_ = 0;
    std::atomic<long> with_labels_{0};
    std::atomic<long> without_labels_{0};
    std::atomic<long> label_errors_{0};
};

}  // namespace voxfuse
