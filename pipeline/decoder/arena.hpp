#pragma once
// The decoder workspace's memory: one block for all its arrays, allocated
// once by Decoder::create(), so that on Linux it can be backed by 2 MB
// transparent huge pages.
//
// Why: the stages read the labels, the regions, the edges and the order
// buffer at random (union-find, counting sort, graph hash table, the
// traversal's records), about 13 MB at 780x580. In 4 KB pages that is ~3 200
// pages, more than a second-level TLB holds (Cortex-A53: 512 entries), so
// many of those reads also walk the page tables; in 2 MB pages it is 7.
// Measured on the development VM (2-core EPYC, tests/bench/ab-compare.sh,
// docs/performance.md, session 13): no difference on the quiet machine;
// about 3 % faster in two of three A/Bs while other processes shared the
// cores (weak evidence). The small TLBs of the boards' cores are the reason
// it is kept; it has not been measured on a board. The kernel decides: with
// transparent huge pages off (/sys/kernel/mm/transparent_hugepage/enabled =
// never) or not built in, the block is in 4 KB pages and everything works
// the same.
//
// Ownership: WorkspaceArena owns the block (DecoderWorkspace::arena); the
// arrays are ArenaArray views into it, valid while the arena lives.
#include <cstddef>
#include <functional>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

namespace stria::pipeline {

// count values of T in memory someone else owns (a WorkspaceArena, or in
// tests a vector): a pointer that says it does not own.
template <typename T>
class ArenaArray {
public:
    ArenaArray() = default;
    explicit ArenaArray(T* data) : data_(data) {}
    T* get() const { return data_; }
    T& operator[](std::size_t i) const { return data_[i]; }
    explicit operator bool() const { return data_ != nullptr; }

private:
    T* data_ = nullptr;
};

class WorkspaceArena {
public:
    WorkspaceArena() = default;
    WorkspaceArena(const WorkspaceArena&) = delete;
    WorkspaceArena& operator=(const WorkspaceArena&) = delete;

    // Plans count value-initialised Ts (as std::make_unique<T[]>(count)
    // gives) on a 64-byte boundary; `array` points to them once allocate()
    // has run. `array` must outlive the call to allocate().
    template <typename T>
    void reserve(ArenaArray<T>& array, std::size_t count)
    {
        static_assert(std::is_trivially_destructible_v<T>, "the arena never runs destructors");
        static_assert(alignof(T) <= kAlignment);
        const std::size_t offset = planned_;
        planned_ = roundUp(offset + count * sizeof(T) + kRedZone, kAlignment);
        arrays_.push_back({offset, count * sizeof(T), [&array, offset, count](std::byte* base) {
                               T* data = reinterpret_cast<T*>(base + offset);
                               std::uninitialized_value_construct_n(data, count);
                               array = ArenaArray<T>(data);
                           }});
    }

    // Allocates the planned arrays in one block and points them to their
    // places (once). Returns the block's bytes (the planned bytes rounded up
    // to whole 4 KB pages). Throws std::bad_alloc when the memory is not there.
    std::size_t allocate();

    // Bytes of the block (0 before allocate()).
    std::size_t bytes() const { return bytes_; }
    // Whether the kernel was asked to back the block with huge pages (it may
    // still not: see /proc/self/smaps, AnonHugePages).
    bool hugePagesAdvised() const { return hugePagesAdvised_; }

    static constexpr std::size_t kAlignment = 64;  // a cache line
    static constexpr std::size_t kHugePage = std::size_t{2} << 20;

private:
    static std::size_t roundUp(std::size_t n, std::size_t to) { return (n + to - 1) / to * to; }
#if defined(__SANITIZE_ADDRESS__)
    // Under AddressSanitizer a poisoned line after each array, so that a
    // stage running past its array's end is still reported, as it was when
    // every array was a heap block of its own.
    static constexpr std::size_t kRedZone = kAlignment;
#else
    static constexpr std::size_t kRedZone = 0;
#endif

    struct Planned {
        std::size_t offset, size;
        std::function<void(std::byte*)> place;
    };
    struct Release {
        std::size_t bytes;
        bool mapped;
        void operator()(std::byte* block) const;
    };

    std::vector<Planned> arrays_;
    std::size_t planned_ = 0, bytes_ = 0;
    bool hugePagesAdvised_ = false;
    std::unique_ptr<std::byte, Release> block_{nullptr, Release{0, false}};
};

}  // namespace stria::pipeline
