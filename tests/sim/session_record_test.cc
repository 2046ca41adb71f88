// Recorded sessions (sim/session_record.h): a round trip is bit-exact, nothing pushed before
// stop() is lost, and every kind of corruption is reported with the file and the record named.
#include "sim/session_record.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>

#include "reference/core/io.h"

namespace dentsim {
namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("dentsim_session_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

DeviceSample make(int dof, long k) {
  DeviceSample s;
  s.q = VecX::LinSpaced(dof, 0.1 * k, 0.1 * k + 1.0);
  s.qd = VecX::Constant(dof, -0.5 * k);
  s.t = 1e-3 * k;
  return s;
}

// Writes n ticks of a 6-DoF session.
std::string write_session(const std::string& name, long n, std::size_t capacity = 1024) {
  const std::string path = temp_path(name);
  SessionHeader h;
  h.dof = 6;
  h.tick_rate_hz = 1000.0;
  h.context = "{\"scene\":\"drill\"}";
  SessionWriter w(path, h, capacity);
  // A full ring refuses a tick (counted); here the producer retries until the writer made room,
  // so the ring wraps around many times and every tick must still arrive intact and in order.
  std::uint64_t refused = 0;
  for (long k = 0; k < n; ++k) {
    const DeviceSample s = make(6, k);
    while (
        !w.push(static_cast<std::uint64_t>(k), s, 0.01 * s.q, static_cast<std::uint32_t>(k % 3))) {
      ++refused;
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  }
  w.stop();
  EXPECT_EQ(w.written(), static_cast<std::uint64_t>(n));
  EXPECT_EQ(w.dropped(), refused);
  return path;
}

std::vector<char> slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void spit(const std::string& path, const std::vector<char>& b) {
  std::ofstream(path, std::ios::binary).write(b.data(), static_cast<std::streamsize>(b.size()));
}

std::string error_of(const std::string& path) {
  try {
    read_session(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SessionRecord, Crc32MatchesTheStandardCheckValue) {
  // The CRC-32/IEEE check value of "123456789".
  EXPECT_EQ(crc32("123456789", 9), 0xCBF43926u);
}

TEST(SessionRecord, RoundTripIsBitExact) {
  // 2000 ticks through a 256-slot ring: the writer drains while the producer runs.
  const std::string path = write_session("roundtrip", 2000, 256);
  const Session s = read_session(path);
  EXPECT_EQ(s.header.dof, 6);
  EXPECT_EQ(s.header.tick_rate_hz, 1000.0);
  EXPECT_EQ(s.header.context, "{\"scene\":\"drill\"}");
  ASSERT_EQ(s.records.size(), 2000u);
  for (long k = 0; k < 2000; ++k) {
    const SessionRecord& r = s.records[static_cast<std::size_t>(k)];
    const DeviceSample e = make(6, k);
    EXPECT_EQ(r.tick, static_cast<std::uint64_t>(k));
    EXPECT_EQ(r.sample.t, e.t);
    EXPECT_EQ(r.sample.q, e.q);
    EXPECT_EQ(r.sample.qd, e.qd);
    EXPECT_EQ(r.tau, VecX(0.01 * e.q));
    EXPECT_EQ(r.contacts, static_cast<std::uint32_t>(k % 3));
  }
  // Size: header (8 + 4 + 4 + 8 + 4 + context + 4) + 2000 records of 8 + 8 (1 + 18) + 4 + 4.
  EXPECT_EQ(std::filesystem::file_size(path), 32u + 17u + 2000u * (8u + 8u * 19u + 8u));
  std::remove(path.c_str());
}

TEST(SessionRecord, FullRingDropsAndCountsNothingSilently) {
  const std::string path = temp_path("full");
  SessionHeader h;
  h.dof = 2;
  SessionWriter w(path, h, 4);
  // The writer sleeps between drains; 10000 pushes without pause overrun 4 slots.
  std::uint64_t accepted = 0;
  for (int k = 0; k < 10000; ++k) accepted += w.push(k, make(2, k), VecX::Zero(2), 0) ? 1 : 0;
  w.stop();
  EXPECT_EQ(accepted + w.dropped(), 10000u);
  EXPECT_EQ(w.written(), accepted);
  EXPECT_EQ(read_session(path).records.size(), accepted);
  std::remove(path.c_str());
}

TEST(SessionRecord, CorruptionIsNamed) {
  const std::string path = write_session("corrupt", 10);
  const std::vector<char> good = slurp(path);
  const std::size_t header = 32 + 17, rec = 8 + 8 * 19 + 8;

  std::vector<char> b = good;
  b[0] = 'X';
  spit(path, b);
  EXPECT_NE(error_of(path).find(path + ": not a dentsim session (bad magic"), std::string::npos);

  b = good;
  b[8] = 2;  // version 2
  spit(path, b);
  EXPECT_NE(error_of(path).find(path + ": version 2, this dentsim reads version 1"),
            std::string::npos);

  b = good;
  b[30] ^= 1;  // a byte of the context
  spit(path, b);
  EXPECT_NE(error_of(path).find(path + ": bad header checksum"), std::string::npos);

  b = good;
  b[header + 3 * rec + 20] ^= 1;  // a byte of q in record 3
  spit(path, b);
  EXPECT_NE(error_of(path).find(path + ": bad checksum in record 3 at byte " +
                                std::to_string(header + 3 * rec)),
            std::string::npos);

  b = good;
  b.resize(header + 7 * rec + 5);  // record 7 cut after 5 bytes
  spit(path, b);
  EXPECT_NE(error_of(path).find(path + ": truncated record 7 at byte " +
                                std::to_string(header + 7 * rec) + " (5 of " + std::to_string(rec) +
                                " bytes)"),
            std::string::npos);

  b = good;
  b.resize(20);
  spit(path, b);
  EXPECT_NE(error_of(path).find(path + ": truncated header"), std::string::npos);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace dentsim
