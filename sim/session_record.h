// Recorded sessions (issue #15): every servo tick's device sample, command and contact count,
// written by a bounded writer thread so the servo tick never touches the file system, and read
// back for `dentsim replay` (differential testing on data recorded from hardware).
//
// File format, version 1, little-endian (x86-64), IEEE-754 doubles:
//   header  "DSIMREC\0" (8 bytes) | u32 version = 1 | u32 dof | f64 tick_rate_hz |
//           u32 context_bytes | context (UTF-8, e.g. the scene and pipeline as JSON) |
//           u32 CRC-32 of everything before it in the header
//   record  u64 tick | f64 t [s] | f64 q[dof] [rad] | f64 qd[dof] [rad/s] | f64 tau[dof] [N m]
//           (the command the pipeline produced) | u32 contact count | u32 CRC-32 of the record's
//           bytes before it
// The file holds the header and whole records only; a shorter tail is a truncated record.
// CRC-32 is the IEEE 802.3 polynomial (0xEDB88320 reflected), as zlib's crc32().
//
// Writer: push() (servo thread) copies one tick into a lock-free single-producer single-consumer
// ring of fixed capacity (no allocation, never blocks, never throws; a full ring drops the tick
// and counts it); the writer thread drains the ring to the file. stop() (or the destructor) lets
// the writer drain everything pushed, then flushes and closes: nothing pushed before a fault or
// stop is lost.
#pragma once

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "reference/core/device_model.h"

namespace dentsim {

inline constexpr char kSessionMagic[8] = {'D', 'S', 'I', 'M', 'R', 'E', 'C', '\0'};
inline constexpr std::uint32_t kSessionVersion = 1;

std::uint32_t crc32(const void* data, std::size_t n, std::uint32_t crc = 0);

struct SessionHeader {
  std::uint32_t version = kSessionVersion;
  int dof = 0;
  double tick_rate_hz = 1000.0;
  std::string context;
};

struct SessionRecord {
  std::uint64_t tick = 0;
  DeviceSample sample;  // q, qd, t
  VecX tau;             // commanded torque [N m]
  std::uint32_t contacts = 0;
};

class SessionWriter {
 public:
  // Opens `path` (truncating) and writes the header; starts the writer thread. `capacity` ticks
  // fit in the ring (rounded up to a power of two). Throws InputError naming the path when the
  // file cannot be created.
  SessionWriter(const std::string& path, const SessionHeader& header, std::size_t capacity = 65536);
  ~SessionWriter();
  SessionWriter(const SessionWriter&) = delete;
  SessionWriter& operator=(const SessionWriter&) = delete;

  // Servo thread: one tick. False when the ring was full (the tick is dropped and counted).
  bool push(std::uint64_t tick, const DeviceSample& s, const VecX& tau,
            std::uint32_t contacts) noexcept;
  // Drains, flushes and closes (idempotent). Throws std::runtime_error naming the path if a write
  // failed.
  void stop();

  std::uint64_t written() const { return written_.load(); }
  std::uint64_t dropped() const { return dropped_.load(); }
  std::size_t record_bytes() const { return record_bytes_; }

 private:
  void run();
  void write_slot(std::size_t slot);

  std::string path_;
  std::FILE* file_ = nullptr;
  int dof_ = 0;
  std::size_t record_bytes_ = 0, stride_ = 0, mask_ = 0;
  std::vector<unsigned char> ring_;             // capacity x stride_ bytes, preallocated
  std::vector<unsigned char> out_;              // one encoded record (writer thread)
  std::atomic<std::size_t> head_{0}, tail_{0};  // head: next to write (producer); tail: consumer
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> written_{0}, dropped_{0};
  bool write_failed_ = false;
  std::thread thread_;
};

struct Session {
  SessionHeader header;
  std::vector<SessionRecord> records;
};

// Reads a whole session. Throws InputError naming the file and, for a record, its index and byte
// offset: not a session file (bad magic), unsupported version, bad header or record checksum,
// truncated header or record.
Session read_session(const std::string& path);
// The same from the file's bytes (`path` names it in messages; the fuzz target's entry).
Session parse_session(const std::string& bytes, const std::string& path);

}  // namespace dentsim
