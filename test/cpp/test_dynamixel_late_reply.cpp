// Late replies. Protocol 2.0 status packets carry nothing that ties them to
// their request (ID, error, params only): a reply that arrives after its deadline used to be taken
// as the answer to the next request of the same length (at start-up, the operating mode 3 read as
// Hardware Error Status: "hardware error (input_voltage, bit 1)"). Protocol2Bus now drains the line
// after a failed transaction and verifies the next single-servo read by reading it again.
//
// The scripted port below decides *when* a reply arrives by events, not by time, so the tests do
// not depend on the machine's load: on time, just after the deadline (the next read of the port
// gets it), or after the next request was sent (ahead of that request's own reply).
#include <gtest/gtest.h>

#include <array>
#include <deque>
#include <thread>
#include <vector>

#include "snake_autonomy/dynamixel/control_table.hpp"
#include "snake_autonomy/dynamixel/protocol2_bus.hpp"

namespace dx = snake_autonomy::dynamixel;

namespace {

using Bytes = std::vector<std::uint8_t>;

enum class When { kOnTime, kJustAfterDeadline, kAfterNextRequest, kNever };

class LatePort : public dx::Transport {
 public:
  LatePort() {
    for (auto& m : memory) m.fill(0);
  }
  bool is_open() const noexcept override { return true; }
  bool write_all(const std::uint8_t* data, std::size_t size) noexcept override {
    ++requests;
    // A reply held "until the next request" reaches the port now, before this request's own.
    for (const Bytes& b : after_next_request) available.insert(available.end(), b.begin(), b.end());
    after_next_request.clear();
    const Bytes reply = respond(data, size);
    const When when = script.empty() ? When::kOnTime : script.front();
    if (!script.empty()) script.pop_front();
    switch (when) {
      case When::kOnTime: available.insert(available.end(), reply.begin(), reply.end()); break;
      case When::kJustAfterDeadline: after_deadline.push_back(reply); break;
      case When::kAfterNextRequest: after_next_request.push_back(reply); break;
      case When::kNever: break;
    }
    return true;
  }
  long read_some(std::uint8_t* buffer, std::size_t capacity, dx::SteadyTime deadline) noexcept override {
    if (deadline_seen) {  // the port is read again after a deadline passed: the late reply is here
      for (const Bytes& b : after_deadline) available.insert(available.begin(), b.begin(), b.end());
      after_deadline.clear();
    }
    if (available.empty()) {
      std::this_thread::sleep_until(deadline);
      deadline_seen = true;
      return 0;
    }
    const std::size_t n = std::min(capacity, available.size());
    std::copy(available.begin(), available.begin() + static_cast<long>(n), buffer);
    available.erase(available.begin(), available.begin() + static_cast<long>(n));
    return static_cast<long>(n);
  }
  void discard_input() noexcept override {  // TCIFLUSH: what has arrived, not what is on its way
    available.clear();
    deadline_seen = false;
  }
  int baud_bps() const noexcept override { return 1000000; }

  std::array<std::array<std::uint8_t, 256>, 4> memory{};
  std::deque<When> script;  // when the reply to each next request arrives
  int requests = 0;

 private:
  Bytes respond(const std::uint8_t* data, std::size_t size) const {
    std::uint8_t scratch[dx::kMaxPacketBytes];
    dx::Packet p;
    if (dx::parse_packet(data, size, scratch, sizeof scratch, &p).status != dx::ParseStatus::kOk) return {};
    if (p.id >= memory.size()) return {};
    Bytes out(dx::kMaxPacketBytes);
    const auto& m = memory[p.id];
    if (p.instruction == dx::instruction::kRead && p.n_params == 4) {
      const std::size_t address = p.params[0] | (p.params[1] << 8), length = p.params[2] | (p.params[3] << 8);
      out.resize(dx::encode_status(p.id, 0, m.data() + address, length, out.data(), out.size()));
    } else if (p.instruction == dx::instruction::kWrite) {
      out.resize(dx::encode_status(p.id, 0, nullptr, 0, out.data(), out.size()));
    } else {
      out.clear();
    }
    return out;
  }

  Bytes available;
  std::vector<Bytes> after_deadline, after_next_request;
  bool deadline_seen = false;
};

constexpr std::uint16_t kOperatingMode = 11, kHardwareErrorStatus = 70, kReturnDelay = 9;

struct LateReplyFixture : ::testing::Test {
  LatePort port;
  dx::Protocol2Bus bus{port, dx::BusTiming{0.002, 0.0, 1.5}};
  void SetUp() override {
    port.memory[1][kOperatingMode] = 3;  // position control
    port.memory[1][kReturnDelay] = 250;  // the factory value
    port.memory[1][kHardwareErrorStatus] = 0;
  }
  std::uint8_t read1(std::uint16_t address, dx::Status* status) {
    std::uint8_t value = 0xEE, err = 0;
    *status = bus.read(1, address, 1, &value, &err);
    return value;
  }
};

}  // namespace

TEST_F(LateReplyFixture, ReplyJustAfterItsDeadlineIsDrainedNotTakenByTheNextRead) {
  port.script = {When::kJustAfterDeadline};
  dx::Status s;
  read1(kOperatingMode, &s);
  EXPECT_EQ(s, dx::Status::kTimeout);
  // Before the fix this read returned 3 (the operating mode): a hardware error that is not there.
  const std::uint8_t hw = read1(kHardwareErrorStatus, &s);
  EXPECT_EQ(s, dx::Status::kOk);
  EXPECT_EQ(hw, 0) << "the late reply to the operating-mode read was taken as Hardware Error Status";
  EXPECT_EQ(bus.counters().drains, 1u);
  EXPECT_EQ(bus.counters().late_bytes, dx::kStatusOverhead + 1);  // the one late 1-byte reply
  EXPECT_EQ(bus.counters().verify_mismatches, 0u);
}

TEST_F(LateReplyFixture, ReplyAfterTheNextRequestIsRefusedByTheVerifyingReRead) {
  // Later than any drain could wait: it reaches the port after the next request was sent, ahead
  // of that request's own reply (same ID, same length: nothing in the packet tells them apart).
  port.script = {When::kAfterNextRequest};
  dx::Status s;
  read1(kOperatingMode, &s);
  EXPECT_EQ(s, dx::Status::kTimeout);
  EXPECT_TRUE(bus.suspect());
  const std::uint8_t delay = read1(kReturnDelay, &s);
  EXPECT_EQ(s, dx::Status::kOk);
  EXPECT_EQ(delay, 250) << "the operating mode (3) was accepted as the return delay";
  EXPECT_GE(bus.counters().verify_mismatches, 1u);
  EXPECT_FALSE(bus.suspect());
  // Once a verified read agreed, reads are single again: one request each.
  const int before = port.requests;
  EXPECT_EQ(read1(kOperatingMode, &s), 3);
  EXPECT_EQ(s, dx::Status::kOk);
  EXPECT_EQ(port.requests - before, 1);
}

TEST_F(LateReplyFixture, LateWriteStatusAfterARead) {
  // A late 1-byte read reply is not a WRITE's status (no data): it is refused as malformed and the
  // bus drains, it never confirms the write.
  port.script = {When::kAfterNextRequest, When::kOnTime};
  dx::Status s;
  read1(kOperatingMode, &s);
  EXPECT_EQ(s, dx::Status::kTimeout);
  const std::uint8_t on = 1;
  std::uint8_t err = 0;
  EXPECT_EQ(bus.write(1, 64, &on, 1, &err), dx::Status::kMalformed);
  EXPECT_EQ(bus.counters().drains, 2u);
}

TEST_F(LateReplyFixture, AServoThatNeverAnswersStillTimesOut) {
  port.script = {When::kNever, When::kNever};
  dx::Status s;
  read1(kOperatingMode, &s);
  EXPECT_EQ(s, dx::Status::kTimeout);
  read1(kOperatingMode, &s);
  EXPECT_EQ(s, dx::Status::kTimeout);  // not kMalformed: the caller sees what happened
  EXPECT_EQ(bus.counters().timeouts, 2u);
  EXPECT_EQ(bus.counters().late_bytes, 0u);
  // The servo comes back: the verified read takes two requests and returns its value.
  const int before = port.requests;
  EXPECT_EQ(read1(kOperatingMode, &s), 3);
  EXPECT_EQ(s, dx::Status::kOk);
  EXPECT_EQ(port.requests - before, 2);
}
