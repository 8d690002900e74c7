#pragma once
// The keyframes the relocaliser knows: fern codes of well-tracked frames with their poses, at most
// `capacity` of them. A frame becomes a keyframe only when its code differs enough from every stored
// one, so the database holds distinct views rather than runs of near-identical frames. When full, a
// new keyframe replaces the oldest (a camera that moves on keeps the views near it).

#include <vector>

#include "voxfuse/core/Math.h"
#include "voxfuse/engines/FernEncoder.h"

namespace voxfuse {

struct Keyframe {
    FernCode code;
    Mat4f T_world_camera = Mat4f::identity();
    int frame_index = -1;  // the frame it was made from (RGBDFrame::index)
};

struct KeyframeMatch {
    int keyframe = -1;          // index into the database
    float dissimilarity = 1.f;  // fernDissimilarity of the codes
};

class KeyframeDatabase {
public:
    explicit KeyframeDatabase(int capacity);

    // The up to k keyframes nearest to `code`, nearest first; equally near ones in the order they were
    // stored.
    std::vector<KeyframeMatch> nearest(const FernCode& code, int k) const;
    // Stores the frame when no keyframe lies within `min_dissimilarity` of its code. Returns whether it
    // was stored.
    bool addIfNovel(const FernCode& code, const Mat4f& T_world_camera, int frame_index, float min_dissimilarity);

    const Keyframe& keyframe(int i) const { return keyframes_[std::size_t(i)]; }
    // Every keyframe, oldest first (as a map file saves them), and the database made of such a list
    // again (the newest `capacity` of them).
    std::vector<Keyframe> oldestFirst() const;
    void assign(std::vector<Keyframe> oldest_first);
    int size() const { return int(keyframes_.size()); }
    int capacity() const { return capacity_; }
    void clear();

private:
    int capacity_;
    std::vector<Keyframe> keyframes_;
    int oldest_ = 0;  // the slot a new keyframe takes once the database is full
};

}  // namespace voxfuse
