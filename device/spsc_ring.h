// A lock-free single-producer single-consumer ring of records of fixed size (copying one must not
// allocate: plain structs, fixed-size Eigen types), of fixed capacity allocated up front: push()
// (the servo thread, e.g. inside the vendor's scheduler callback) never allocates, blocks or
// throws, and returns false when the ring is full (the caller counts the drop); pop() (one other
// thread) takes the oldest record.
//
// Indices only grow (head: next slot to fill, tail: next to take; both modulo the power-of-two
// capacity): head - tail is the number of records held. The producer publishes a record with a
// release store of head after writing it; the consumer reads it after an acquire load of head,
// and frees the slot with a release store of tail.
#pragma once

#include <atomic>
#include <bit>
#include <cstddef>
#include <type_traits>
#include <vector>

namespace dentsim {

template <typename T>
class SpscRing {
  static_assert(std::is_default_constructible_v<T> && std::is_copy_assignable_v<T>,
                "SpscRing holds default-constructible, copy-assignable records");

 public:
  // At least `capacity` records (rounded up to a power of two, at least 2).
  explicit SpscRing(std::size_t capacity)
      : slots_(std::bit_ceil(capacity < 2 ? std::size_t{2} : capacity)), mask_(slots_.size() - 1) {}
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  // Producer. False (nothing written) when the ring is full.
  bool push(const T& value) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) > mask_) return false;
    slots_[head & mask_] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  // Consumer. False when the ring is empty.
  bool pop(T& out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return false;
    out = slots_[tail & mask_];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  std::size_t capacity() const { return slots_.size(); }

 private:
  std::vector<T> slots_;
  std::size_t mask_;
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
};

}  // namespace dentsim
