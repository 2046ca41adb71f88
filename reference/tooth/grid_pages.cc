// The voxel grid's empty pages (reference/tooth/grid_pages.h).
#include "reference/tooth/grid_pages.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif
#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

#include <algorithm>
#include <cstring>

namespace dentsim {

namespace {

std::size_t page_bytes() {
#if defined(__linux__)
  static const long page_size = sysconf(_SC_PAGESIZE);
  return page_size > 0 ? static_cast<std::size_t>(page_size) : 0;
#else
  return 0;
#endif
}

bool all_zero(const std::uint8_t* p, std::size_t size) {
  std::uint64_t any = 0;
  std::size_t i = 0;
  for (; i + 8 <= size; i += 8) {
    std::uint64_t word;
    std::memcpy(&word, p + i, 8);
    any |= word;
  }
  for (; i < size; ++i) any |= p[i];
  return any == 0;
}

}  // namespace

void release_zero_pages(const std::uint8_t* begin, const std::uint8_t* end) {
#if defined(__linux__)
  const std::uintptr_t page = page_bytes();
  if (page == 0) return;
  const std::uintptr_t lo = (reinterpret_cast<std::uintptr_t>(begin) + page - 1) / page * page;
  const std::uintptr_t hi = reinterpret_cast<std::uintptr_t>(end) / page * page;
  if (hi > lo) madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_DONTNEED);
#else
  (void)begin;
  (void)end;
#endif
}

std::size_t release_empty_pages(const VoxelGrid& grid) {
  const std::size_t page = page_bytes();
  if (page == 0 || grid.voxels.empty()) return 0;
  const std::uint8_t* data = grid.voxels.data();
  const std::uint8_t* end = data + grid.voxels.size();
  // The whole pages of the storage, in runs of empty ones (one madvise a run).
  const auto first = reinterpret_cast<std::uintptr_t>(data);
  const std::uint8_t* p = data + ((page - first % page) % page);
  const std::uint8_t* run = nullptr;  // the start of the current run of empty pages
  std::size_t released = 0;
  for (; p + page <= end; p += page) {
    if (all_zero(p, page)) {
      if (run == nullptr) run = p;
      continue;
    }
    if (run != nullptr) {
      release_zero_pages(run, p);
      released += static_cast<std::size_t>(p - run);
      run = nullptr;
    }
  }
  if (run != nullptr) {
    release_zero_pages(run, p);
    released += static_cast<std::size_t>(p - run);
  }
  return released;
}

VoxelGrid::VoxelGrid(const VoxelGrid& other)
    : n(other.n), origin(other.origin), voxel_size(other.voxel_size) {
  const std::size_t size = other.voxels.size();
  voxels.reserve(size);
  const std::uint8_t* src = other.voxels.data();
  const std::size_t page = page_bytes();
  if (page == 0) {
    voxels.assign(src, src + size);
    return;
  }
  // Page by page of the copy's storage (the first piece up to its first page boundary). Reading a
  // released page may take it back (a system without a shared zero page, such as this project's
  // VMs): the whole pages of a run of empty pieces, the copy's and the source's (whose content is
  // unchanged and whose pages need not be aligned with the copy's), go back every kBatch pieces
  // and at the run's end, so at most kBatch + 1 such pages of each are resident at once.
  constexpr std::size_t kBatch = 64;
  const auto first = reinterpret_cast<std::uintptr_t>(voxels.data());
  const auto base = reinterpret_cast<std::uintptr_t>(src);
  std::size_t to = std::min(size, (page - first % page) % page);
  std::size_t empty_from = 0, pieces = 0;  // the current run of empty pieces
  const auto release_run = [&](std::size_t end) {
    release_zero_pages(voxels.data() + empty_from, voxels.data() + end);
    release_zero_pages(src + empty_from, src + end);
  };
  for (std::size_t from = 0; from < size; from = to, to = std::min(size, to + page)) {
    voxels.insert(voxels.end(), src + from, src + to);
    if (!all_zero(src + from, to - from)) {
      release_run(from);
      empty_from = to;
      pieces = 0;
    } else if (++pieces == kBatch) {
      // The run goes on from the last page boundary of the source before `to` (the copy's is
      // `to` itself: its pieces end on its pages' boundaries).
      release_run(to);
      const std::uintptr_t boundary = (base + to) / page * page;
      if (boundary > base) empty_from = std::max(empty_from, std::size_t{boundary - base});
      pieces = 0;
    }
  }
  release_run(size);
}

VoxelGrid& VoxelGrid::operator=(const VoxelGrid& other) {
  if (this != &other) *this = VoxelGrid(other);
  return *this;
}

void release_free_heap() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

}  // namespace dentsim
