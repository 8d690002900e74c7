#pragma once
// The global cache of swapping (section 5 of the InfiniTAM report): where voxel blocks live while they
// are out of the active voxel array, in host memory or in a file on disk. A block is found through its
// hash entry (HashTableState::stored_slot holds its slot), so the host never searches; slots are
// reused as blocks come back, and storage grows with the blocks stored, not with the table.
//
// Blocks move in batches through the swapping engine's fixed-size transfer buffers. Disk errors (a
// full disk included) are IoErrors naming the file.

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace voxfuse {

class GlobalCache {
public:
    // A cache of blocks of `block_bytes` bytes: in host memory, or in `swap_file` when the path is not
    // empty (a new file, never an existing one, unlinked at once: the space it takes comes back when
    // the cache goes, however the process ends).
    explicit GlobalCache(std::size_t block_bytes, const std::string& swap_file = "");
    ~GlobalCache();
    GlobalCache(const GlobalCache&) = delete;
    GlobalCache& operator=(const GlobalCache&) = delete;

    std::size_t blockBytes() const { return block_bytes_; }
    bool onDisk() const { return fd_ >= 0; }
    const std::string& swapFile() const { return path_; }
    int storedBlocks() const { return int(slot_count_ - free_slots_.size()); }
    // Bytes held in host memory for stored blocks (0 on disk), and on disk.
    std::size_t memoryBytes() const { return onDisk() ? 0 : std::size_t(slot_count_) * block_bytes_; }
    std::size_t fileBytes() const { return onDisk() ? std::size_t(slot_count_) * block_bytes_ : 0; }

    // Stores `count` blocks (consecutive in `blocks`) in free slots, written to `slots`.
    void store(const void* blocks, int count, int* slots);
    // Reads the blocks of `count` slots into consecutive places of `blocks` and frees the slots.
    void take(const int* slots, int count, void* blocks);
    // Reads one block without freeing its slot (saving a map).
    void read(int slot, void* block) const;

private:
    unsigned char* memorySlot(int slot) const;
    void checkSlot(int slot) const;

    std::size_t block_bytes_;
    std::string path_;
    int fd_ = -1;
    int slot_count_ = 0;                                    // slots ever used
    std::vector<int> free_slots_;                           // reused first, lowest last
    std::vector<std::unique_ptr<unsigned char[]>> chunks_;  // host memory: kSlotsPerChunk blocks each
    static constexpr int kSlotsPerChunk = 1024;
};

}  // namespace voxfuse
