// The global cache in host memory (chunks of 1024 blocks) or in a swap file (pread/pwrite at the slot's offset).

#include "voxfuse/objects/GlobalCache.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "voxfuse/core/Error.h"

namespace voxfuse {

GlobalCache::GlobalCache(std::size_t block_bytes, const std::string& swap_file)
    : block_bytes_(block_bytes), path_(swap_file) {
    if (block_bytes_ == 0) throw ConfigError("global cache: blocks of 0 bytes");
    if (path_.empty()) return;
    // A new file only: the swap file is deleted at once, so an existing path (a map, a user's file)
    // would be lost.
    fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd_ < 0 && errno == EEXIST)
        throw IoError(path_,
                      "the swap file must be a new path: it is deleted as soon as it is opened, and this one exists");
    if (fd_ < 0) throw IoError(path_, std::string("cannot create the swap file: ") + std::strerror(errno));
    // Unlinked at once: the open file keeps its blocks, the space comes back however the run ends, and
    // a later cache on the same path makes a file of its own.
    ::unlink(path_.c_str());
}

GlobalCache::~GlobalCache() {
    if (fd_ >= 0) ::close(fd_);
}

unsigned char* GlobalCache::memorySlot(int slot) const {
    return chunks_[std::size_t(slot / kSlotsPerChunk)].get() + std::size_t(slot % kSlotsPerChunk) * block_bytes_;
}

void GlobalCache::checkSlot(int slot) const {
    if (slot < 0 || slot >= slot_count_)
        throw Error("global cache: slot " + std::to_string(slot) + " was never stored");
}

void GlobalCache::store(const void* blocks, int count, int* slots) {
    const auto* bytes = static_cast<const unsigned char*>(blocks);
    for (int k = 0; k < count; ++k) {
        int slot;
        if (!free_slots_.empty()) {
            slot = free_slots_.back();
            free_slots_.pop_back();
        } else {
            slot = slot_count_++;
            if (fd_ < 0 && slot / kSlotsPerChunk >= int(chunks_.size()))
                chunks_.push_back(std::make_unique<unsigned char[]>(std::size_t(kSlotsPerChunk) * block_bytes_));
        }
        const unsigned char* block = bytes + std::size_t(k) * block_bytes_;
        if (fd_ < 0) {
            std::memcpy(memorySlot(slot), block, block_bytes_);
        } else {
            const off_t offset = off_t(slot) * off_t(block_bytes_);
            std::size_t done = 0;
            while (done < block_bytes_) {
                const ssize_t n = ::pwrite(fd_, block + done, block_bytes_ - done, offset + off_t(done));
                if (n < 0 && errno == EINTR) continue;
                if (n <= 0)
                    throw IoError(
                        path_, std::string("cannot write to the swap file: ") + std::strerror(n < 0 ? errno : ENOSPC));
                done += std::size_t(n);
            }
        }
        slots[k] = slot;
    }
}

void GlobalCache::read(int slot, void* block) const {
    checkSlot(slot);
    if (fd_ < 0) {
        std::memcpy(block, memorySlot(slot), block_bytes_);
        return;
    }
    auto* out = static_cast<unsigned char*>(block);
    const off_t offset = off_t(slot) * off_t(block_bytes_);
    std::size_t done = 0;
    while (done < block_bytes_) {
        const ssize_t n = ::pread(fd_, out + done, block_bytes_ - done, offset + off_t(done));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0)
            throw IoError(path_, n < 0 ? std::string("cannot read the swap file: ") + std::strerror(errno)
                                       : "the swap file is shorter than its blocks");
        done += std::size_t(n);
    }
}

void GlobalCache::take(const int* slots, int count, void* blocks) {
    auto* out = static_cast<unsigned char*>(blocks);
    for (int k = 0; k < count; ++k) read(slots[k], out + std::size_t(k) * block_bytes_);
    for (int k = count - 1; k >= 0; --k) free_slots_.push_back(slots[k]);
}

}  // namespace voxfuse
