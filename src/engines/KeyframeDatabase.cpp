#include "voxfuse/engines/KeyframeDatabase.h"

#include <algorithm>

#include "voxfuse/core/Error.h"

namespace voxfuse {

KeyframeDatabase::KeyframeDatabase(int capacity) : capacity_(capacity) {
    if (capacity < 1) throw ConfigError("the keyframe database needs room for at least one keyframe");
}

std::vector<KeyframeMatch> KeyframeDatabase::nearest(const FernCode& code, int k) const {
    // A linear scan: 1000 keyframes of 500 ferns are half a million byte compares, well under a millisecond.
    std::vector<KeyframeMatch> all;
    all.reserve(keyframes_.size());
    for (std::size_t i = 0; i < keyframes_.size(); ++i)
        all.push_back({int(i), fernDissimilarity(code, keyframes_[i].code)});
    // Stored order: slot order rotated so that the oldest comes first.
    const auto age = [&](int slot) { return (slot - oldest_ + size()) % std::max(1, size()); };
    const std::size_t n = std::min(all.size(), std::size_t(std::max(0, k)));
    std::partial_sort(all.begin(), all.begin() + std::ptrdiff_t(n), all.end(),
                      [&](const KeyframeMatch& a, const KeyframeMatch& b) {
                          return a.dissimilarity != b.dissimilarity ? a.dissimilarity < b.dissimilarity
                                                                    : age(a.keyframe) < age(b.keyframe);
                      });
    all.resize(n);
    return all;
}

bool KeyframeDatabase::addIfNovel(const FernCode& code, const Mat4f& T_world_camera, int frame_index,
                                  float min_dissimilarity) {
    const std::vector<KeyframeMatch> closest = nearest(code, 1);
    if (!closest.empty() && closest.front().dissimilarity < min_dissimilarity) return false;
    Keyframe keyframe{code, T_world_camera, frame_index};
    if (size() < capacity_) {
        keyframes_.push_back(std::move(keyframe));
    } else {
        keyframes_[std::size_t(oldest_)] = std::move(keyframe);
        oldest_ = (oldest_ + 1) % capacity_;
    }
    return true;
}

std::vector<Keyframe> KeyframeDatabase::oldestFirst() const {
    std::vector<Keyframe> all(keyframes_.begin() + oldest_, keyframes_.end());
    all.insert(all.end(), keyframes_.begin(), keyframes_.begin() + oldest_);
    return all;
}

void KeyframeDatabase::assign(std::vector<Keyframe> oldest_first) {
    const std::size_t drop = oldest_first.size() > std::size_t(capacity_) ? oldest_first.size() - capacity_ : 0;
    keyframes_.assign(std::make_move_iterator(oldest_first.begin() + std::ptrdiff_t(drop)),
                      std::make_move_iterator(oldest_first.end()));
    oldest_ = 0;
}

void KeyframeDatabase::clear() {
    keyframes_.clear();
    oldest_ = 0;
}

}  // namespace voxfuse
