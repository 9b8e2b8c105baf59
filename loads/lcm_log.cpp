#include "loads/lcm_log.h"

#include <array>
#include <vector>

namespace peritwin::loads {

namespace {

constexpr std::uint32_t kSyncWord = 0xEDA1DA01;
constexpr std::size_t kHeaderBytes = 4 + 8 + 8 + 4 + 4;

std::uint64_t read_be(const unsigned char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

}  // namespace

core::Expected<LcmLogScan> scan_lcm_log(
    std::istream& in, const std::string& name, std::string_view channel, std::size_t max_data,
    const std::function<void(std::span<const std::uint8_t>)>& on_data) {
  LcmLogScan scan;
  std::uint64_t offset = 0;  // of the current event
  std::string event_channel;
  std::vector<std::uint8_t> data;
  while (true) {
    std::array<unsigned char, kHeaderBytes> header{};
    in.read(reinterpret_cast<char*>(header.data()), header.size());
    const auto got = static_cast<std::size_t>(in.gcount());
    if (got == 0 && in.eof()) break;
    auto where = [&] {
      return name + ": event " + std::to_string(scan.events + 1) + " at byte " +
             std::to_string(offset) + ": ";
    };
    if (got < 4 || read_be(header.data(), 4) != kSyncWord) {
      return core::failure(where() + "no LCM log sync word (not an LCM log, or corrupt)");
    }
    if (got < kHeaderBytes) return core::failure(where() + "the file ends inside the event header");
    const auto channel_length = static_cast<std::int32_t>(read_be(header.data() + 20, 4));
    const auto data_length = static_cast<std::int32_t>(read_be(header.data() + 24, 4));
    if (channel_length < 1 || channel_length > kMaxLcmLogChannel) {
      return core::failure(where() + "channel length " + std::to_string(channel_length) +
                           " is not in 1.." + std::to_string(kMaxLcmLogChannel));
    }
    if (data_length < 0) {
      return core::failure(where() + "negative data length " + std::to_string(data_length));
    }
    event_channel.resize(static_cast<std::size_t>(channel_length));
    in.read(event_channel.data(), channel_length);
    if (in.gcount() != channel_length) {
      return core::failure(where() + "the file ends inside the channel name");
    }
    const auto size = static_cast<std::size_t>(data_length);
    const bool wanted = event_channel == channel;
    if (wanted && size <= max_data) {
      data.resize(size);
      in.read(reinterpret_cast<char*>(data.data()), data_length);
    } else {
      in.ignore(data_length);
    }
    if (in.gcount() != data_length) {
      return core::failure(where() + "the file ends inside the event's " + std::to_string(size) +
                           " data bytes");
    }
    ++scan.events;
    offset += kHeaderBytes + static_cast<std::size_t>(channel_length) + size;
    if (!wanted) continue;
    ++scan.on_channel;
    if (size > max_data) {
      ++scan.oversized;
      continue;
    }
    on_data(std::span<const std::uint8_t>(data.data(), size));
  }
  if (in.bad()) return core::failure(name + ": read error");
  return scan;
}

}  // namespace peritwin::loads
