// The voxel grid's empty pages (issue #30: a 512^3 grid is 128 MiB, and the field model's run
// keeps two, the servo's tooth and its edit worker's copy). A grid's storage is written whole
// when it is made (zeros) or copied, so every page of it is resident although most hold only
// empty voxels (the tooth fills a fraction of its grid's cube). release_empty_pages hands those
// pages back to the system (Linux: madvise(MADV_DONTNEED) on private anonymous memory, which then
// reads as zeros again): the grid reads the same, and writing a voxel there takes the page back.
#pragma once

#include <cstddef>
#include <cstdint>

#include "reference/tooth/voxel_grid.h"

namespace dentsim {

// Hands the whole memory pages inside [begin, end) back to the system (Linux): the caller wrote
// zeros there, which a private anonymous page (heap memory) reads as again once released; a
// failed madvise, or another system, leaves them as they are.
void release_zero_pages(const std::uint8_t* begin, const std::uint8_t* end);

// Releases the whole pages of grid.voxels that hold only empty voxels (their content does not
// change, hence const), and returns their bytes. Not in a tick (a pass over the grid, syscalls).
std::size_t release_empty_pages(const VoxelGrid& grid);

// Hands the free pages of the malloc arenas back to the system (glibc: malloc_trim(0); elsewhere
// nothing). Memory freed by a phase that is over (a run's rig, a setup's scratch) stays resident
// in the arenas otherwise: blocks below the mmap threshold, which glibc raises up to 32 MiB after
// freeing a larger block, are freed into the heap, which gives back only its top. Not in a tick.
void release_free_heap();

}  // namespace dentsim
