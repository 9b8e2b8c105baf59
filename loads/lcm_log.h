// LCM log files (what lcm-logger writes) read with bounds, for the replay tool's --format lcm-log.
//
// The format (LCM's eventlog.c): events back to back, each the sync word 0xEDA1DA01 (uint32),
// eventnum (int64), timestamp (int64, us), channel length (int32), data length (int32), the
// channel's bytes, the data; all big-endian. LCM 1.3.1's own reader (lcm::LogFile) allocates
// whatever data length an event claims (2 GB from a 40-byte file) and ends the log silently at
// the first malformed event; this one reads only the events it hands out, at most `max_data`
// bytes each, skips the others without storing them, and names the byte offset of anything
// malformed: no sync word where an event starts, a channel length outside 1..kMaxLcmLogChannel, a
// negative data length, or a file that ends inside an event.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <istream>
#include <span>
#include <string>
#include <string_view>

#include "core/expected.h"

namespace peritwin::loads {

/// Longest channel name accepted in a log (LCM's own reader's bound; LCM publishes at most 63).
inline constexpr std::int32_t kMaxLcmLogChannel = 999;

struct LcmLogScan {
  std::int64_t events = 0;      ///< events in the log, all channels
  std::int64_t on_channel = 0;  ///< events on the channel asked for, oversized ones included
  std::int64_t oversized = 0;   ///< events on the channel with more than max_data bytes (skipped)
};

/// Reads every event of the log in `in` (errors name `name`: "name: event 3 at byte 120: ...")
/// and calls on_data with the data of each event on `channel` of at most `max_data` bytes, in log
/// order.
core::Expected<LcmLogScan> scan_lcm_log(
    std::istream& in, const std::string& name, std::string_view channel, std::size_t max_data,
    const std::function<void(std::span<const std::uint8_t>)>& on_data);

}  // namespace peritwin::loads
