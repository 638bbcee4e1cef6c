// WorkspaceArena (arena.hpp): one block, 2 MB-aligned and advised as huge
// pages on Linux.
#include "pipeline/decoder/arena.hpp"

#include <algorithm>
#include <cstdint>

#if defined(__linux__)
#include <sys/mman.h>
#endif
#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/asan_interface.h>
#endif

namespace stria::pipeline {

void WorkspaceArena::Release::operator()(std::byte* block) const
{
#if defined(__SANITIZE_ADDRESS__)
    ASAN_UNPOISON_MEMORY_REGION(block, bytes);
#endif
#if defined(__linux__)
    if (mapped) {
        munmap(block, bytes);
        return;
    }
#endif
    ::operator delete(block, std::align_val_t{kAlignment});
}

std::size_t WorkspaceArena::allocate()
{
    constexpr std::size_t kPage = 4096;
    const std::size_t size = roundUp(std::max(planned_, kAlignment), kPage);
    std::byte* block = nullptr;
    bool mapped = false;
#if defined(__linux__)
    // A huge page needs a 2 MB-aligned 2 MB range of the mapping: map 2 MB
    // more than needed, then return the unaligned head and the rest of the
    // tail (the block keeps only its own pages; its last partial 2 MB stays
    // in 4 KB pages, as the kernel would anyway).
    if (size >= kHugePage) {
        void* raw = mmap(nullptr, size + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (raw == MAP_FAILED) throw std::bad_alloc();
        const auto start = reinterpret_cast<std::uintptr_t>(raw);
        const std::uintptr_t aligned = roundUp(start, kHugePage);
        if (aligned > start) munmap(raw, aligned - start);
        const std::uintptr_t end = start + size + kHugePage;
        if (end > aligned + size) munmap(reinterpret_cast<void*>(aligned + size), end - (aligned + size));
        block = reinterpret_cast<std::byte*>(aligned);
        mapped = true;
        // EINVAL without transparent huge pages in the kernel: 4 KB pages then.
        hugePagesAdvised_ = madvise(block, size, MADV_HUGEPAGE) == 0;
    }
#endif
    if (!mapped) block = static_cast<std::byte*>(::operator new(size, std::align_val_t{kAlignment}));
    block_ = std::unique_ptr<std::byte, Release>(block, Release{size, mapped});
    bytes_ = size;
    // Value-initialising the arrays also touches every page now, at
    // start-up, not in the first decode.
    for (const Planned& a : arrays_) {
        a.place(block);
#if defined(__SANITIZE_ADDRESS__)
        ASAN_POISON_MEMORY_REGION(block + a.offset + a.size, kRedZone);
#endif
    }
    arrays_.clear();
    arrays_.shrink_to_fit();
    return size;
}

}  // namespace stria::pipeline
