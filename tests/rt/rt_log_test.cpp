// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/rt_log.hpp"

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <sstream>

#include "swivel/rt/state_snapshot.hpp"

namespace swivel::rt {
namespace {

std::shared_ptr<spdlog::logger> stream_logger(std::ostringstream& out) {
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(out);
  auto logger = std::make_shared<spdlog::logger>("rt_log_test", sink);
  logger->set_pattern("%l %v");
  return logger;
}

TEST(RtLog, FormatsFaultRecordsWithNameAndDetail) {
  LogRecord r;
  r.cycle = 42;
  r.stamp_s = 1.5;
  r.level = LogLevel::kError;
  r.code = LogCode::kFaultRaised;
  r.text = "safe stop";
  r.values = {static_cast<double>(FaultCode::kNonFiniteSensor), 3.0, 0.0, 0.0};
  copy_text("wheel 2 encoder", r.detail);
  EXPECT_EQ(format_log_record(r),
            "loop cycle 42 t=1.500s: fault non_finite_sensor (#3): safe stop (wheel 2 encoder)");
}

TEST(RtLog, CopyTextTruncatesAndTerminates) {
  std::array<char, 4> out{};
  copy_text("abcdef", out);
  EXPECT_STREQ(out.data(), "abc");
  copy_text(nullptr, out);
  EXPECT_STREQ(out.data(), "");
}

TEST(RtLog, DrainWritesPushedRecordsInOrderAtTheirLevel) {
  std::ostringstream out;
  RtLog log(stream_logger(out));
  LogRecord a;
  a.level = LogLevel::kWarn;
  a.code = LogCode::kCommandRejected;
  a.text = "non-finite velocity command";
  a.values = {17.0, 0.0, 0.0, 0.0};
  LogRecord b;
  b.code = LogCode::kFaultCleared;
  b.values = {static_cast<double>(FaultCode::kLocalizationError), 0.0, 0.0, 0.0};
  ASSERT_TRUE(log.push(a));
  ASSERT_TRUE(log.push(b));
  EXPECT_EQ(log.drain(), 2U);
  const std::string text = out.str();
  const auto first = text.find(
      "warning loop cycle 0 t=0.000s: command_rejected: "
      "non-finite velocity command [17 0 0 0]");
  const auto second = text.find("info loop cycle 0 t=0.000s: fault localization_error cleared");
  ASSERT_NE(first, std::string::npos) << text;
  ASSERT_NE(second, std::string::npos) << text;
  EXPECT_LT(first, second);
  EXPECT_EQ(log.drain(), 0U);
}

TEST(RtLog, CountsAndReportsDroppedRecordsWhenFull) {
  std::ostringstream out;
  RtLog log(stream_logger(out));
  LogRecord r;
  for (std::size_t i = 0; i < RtLog::kCapacity; ++i) ASSERT_TRUE(log.push(r));
  EXPECT_FALSE(log.push(r));
  EXPECT_FALSE(log.push(r));
  EXPECT_EQ(log.dropped(), 2U);
  EXPECT_EQ(log.drain(), RtLog::kCapacity);
  EXPECT_NE(out.str().find("loop log ring full: 2 records dropped"), std::string::npos);
}

TEST(RtLog, ThreadWritesRecordsPushedBeforeStop) {
  std::ostringstream out;
  RtLog log(stream_logger(out));
  log.start(0.001);
  LogRecord r;
  r.text = "hello from the loop";
  ASSERT_TRUE(log.push(r));
  log.stop();  // drains what is left
  EXPECT_NE(out.str().find("hello from the loop"), std::string::npos);
}

}  // namespace
}  // namespace swivel::rt
