#include "sim/session_record.h"

#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "reference/core/io.h"

namespace dentsim {

namespace {

std::array<std::uint32_t, 256> make_crc_table() {
  std::array<std::uint32_t, 256> t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[i] = c;
  }
  return t;
}

template <typename T>
void put(unsigned char*& p, const T& v) {
  std::memcpy(p, &v, sizeof(T));
  p += sizeof(T);
}

template <typename T>
T get(const unsigned char*& p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  p += sizeof(T);
  return v;
}

std::size_t record_size(int dof) {
  return sizeof(std::uint64_t) + sizeof(double) * (1 + 3 * static_cast<std::size_t>(dof)) +
         2 * sizeof(std::uint32_t);
}

}  // namespace

std::uint32_t crc32(const void* data, std::size_t n, std::uint32_t crc) {
  static const std::array<std::uint32_t, 256> table = make_crc_table();
  const auto* p = static_cast<const unsigned char*>(data);
  crc = ~crc;
  for (std::size_t i = 0; i < n; ++i) crc = table[(crc ^ p[i]) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

SessionWriter::SessionWriter(const std::string& path, const SessionHeader& header,
                             std::size_t capacity)
    : path_(path), dof_(header.dof) {
  if (dof_ < 1)
    throw InputError("session " + path + ": dof = " + std::to_string(dof_) + ", expected >= 1");
  file_ = std::fopen(path.c_str(), "wb");
  if (file_ == nullptr) {
    throw InputError("session " + path + ": cannot create the file (" + std::strerror(errno) + ")");
  }
  std::vector<unsigned char> h(8 + 4 + 4 + 8 + 4 + header.context.size() + 4);
  unsigned char* p = h.data();
  std::memcpy(p, kSessionMagic, 8);
  p += 8;
  put(p, kSessionVersion);
  put(p, static_cast<std::uint32_t>(dof_));
  put(p, header.tick_rate_hz);
  put(p, static_cast<std::uint32_t>(header.context.size()));
  std::memcpy(p, header.context.data(), header.context.size());
  p += header.context.size();
  put(p, crc32(h.data(), static_cast<std::size_t>(p - h.data())));
  if (std::fwrite(h.data(), 1, h.size(), file_) != h.size()) {
    std::fclose(file_);
    throw InputError("session " + path + ": cannot write the header");
  }
  std::size_t cap = 1;
  while (cap < capacity) cap <<= 1;
  mask_ = cap - 1;
  record_bytes_ = record_size(dof_);
  stride_ = record_bytes_;
  ring_.assign(cap * stride_, 0);
  out_.assign(record_bytes_, 0);
  thread_ = std::thread([this] { run(); });
}

SessionWriter::~SessionWriter() {
  try {
    stop();
  } catch (const std::exception&) {  // destructor: the failure was counted; nothing to rethrow
  }
}

bool SessionWriter::push(std::uint64_t tick, const DeviceSample& s, const VecX& tau,
                         std::uint32_t contacts) noexcept {
  const std::size_t head = head_.load(std::memory_order_relaxed);
  const std::size_t tail = tail_.load(std::memory_order_acquire);
  if (head - tail > mask_ || s.q.size() != dof_ || s.qd.size() != dof_ || tau.size() != dof_) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  unsigned char* p = ring_.data() + (head & mask_) * stride_;
  unsigned char* const start = p;
  put(p, tick);
  put(p, s.t);
  for (int i = 0; i < dof_; ++i) put(p, s.q[i]);
  for (int i = 0; i < dof_; ++i) put(p, s.qd[i]);
  for (int i = 0; i < dof_; ++i) put(p, tau[i]);
  put(p, contacts);
  put(p, crc32(start, static_cast<std::size_t>(p - start)));
  head_.store(head + 1, std::memory_order_release);
  return true;
}

void SessionWriter::run() {
  for (;;) {
    const std::size_t head = head_.load(std::memory_order_acquire);
    std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head) {
      if (stopping_.load(std::memory_order_acquire) && head_.load() == tail) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      continue;
    }
    for (; tail != head; ++tail) {
      if (!write_failed_ && std::fwrite(ring_.data() + (tail & mask_) * stride_, 1, record_bytes_,
                                        file_) != record_bytes_) {
        write_failed_ = true;
      }
      if (!write_failed_) written_.fetch_add(1, std::memory_order_relaxed);
      tail_.store(tail + 1, std::memory_order_release);
    }
  }
}

void SessionWriter::stop() {
  if (file_ == nullptr) return;
  stopping_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
  const bool close_failed = std::fclose(file_) != 0;
  file_ = nullptr;
  if (write_failed_ || close_failed) {
    throw std::runtime_error("session " + path_ + ": writing failed (disk full?) after " +
                             std::to_string(written_.load()) + " records");
  }
}

Session read_session(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("session " + path + ": cannot open the file");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parse_session(bytes, path);
}

Session parse_session(const std::string& file_bytes, const std::string& path) {
  const std::vector<unsigned char> bytes(file_bytes.begin(), file_bytes.end());
  const std::string where = "session " + path;
  const std::size_t fixed = 8 + 4 + 4 + 8 + 4;
  if (bytes.size() < 8 || std::memcmp(bytes.data(), kSessionMagic, 8) != 0) {
    throw InputError(where + ": not a dentsim session (bad magic; expected \"DSIMREC\")");
  }
  if (bytes.size() < fixed) throw InputError(where + ": truncated header");
  const unsigned char* p = bytes.data() + 8;
  Session s;
  s.header.version = get<std::uint32_t>(p);
  if (s.header.version != kSessionVersion) {
    throw InputError(where + ": version " + std::to_string(s.header.version) +
                     ", this dentsim reads version " + std::to_string(kSessionVersion));
  }
  const std::uint32_t dof = get<std::uint32_t>(p);
  s.header.tick_rate_hz = get<double>(p);
  const std::uint32_t ctx = get<std::uint32_t>(p);
  if (dof < 1 || dof > 64) {
    throw InputError(where + ": header dof = " + std::to_string(dof) + ", expected 1..64");
  }
  if (bytes.size() < fixed + ctx + 4) throw InputError(where + ": truncated header");
  s.header.dof = static_cast<int>(dof);
  s.header.context.assign(reinterpret_cast<const char*>(p), ctx);
  p += ctx;
  const std::size_t header_bytes = fixed + ctx;
  const std::uint32_t hcrc = get<std::uint32_t>(p);
  if (hcrc != crc32(bytes.data(), header_bytes)) {
    throw InputError(where + ": bad header checksum");
  }
  const std::size_t rb = record_size(s.header.dof);
  const std::size_t begin = header_bytes + 4;
  const std::size_t body = bytes.size() - begin;
  const std::size_t n = body / rb;
  if (body % rb != 0) {
    throw InputError(where + ": truncated record " + std::to_string(n) + " at byte " +
                     std::to_string(begin + n * rb) + " (" + std::to_string(body % rb) + " of " +
                     std::to_string(rb) + " bytes)");
  }
  s.records.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const unsigned char* r = bytes.data() + begin + k * rb;
    const unsigned char* q = r;
    SessionRecord& rec = s.records[k];
    rec.tick = get<std::uint64_t>(q);
    rec.sample.t = get<double>(q);
    rec.sample.q.resize(dof);
    rec.sample.qd.resize(dof);
    rec.tau.resize(dof);
    for (std::uint32_t i = 0; i < dof; ++i) rec.sample.q[i] = get<double>(q);
    for (std::uint32_t i = 0; i < dof; ++i) rec.sample.qd[i] = get<double>(q);
    for (std::uint32_t i = 0; i < dof; ++i) rec.tau[i] = get<double>(q);
    rec.contacts = get<std::uint32_t>(q);
    const std::uint32_t c = get<std::uint32_t>(q);
    if (c != crc32(r, rb - 4)) {
      throw InputError(where + ": bad checksum in record " + std::to_string(k) + " at byte " +
                       std::to_string(begin + k * rb));
    }
  }
  return s;
}

}  // namespace dentsim
