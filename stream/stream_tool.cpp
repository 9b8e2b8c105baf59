#include "stream/stream_tool.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include "core/fnv1a.h"
#include "loads/state_text.h"

namespace peritwin::stream {

namespace {

namespace st = loads::state_text;
constexpr std::string_view kTag = "peritwin-stream-state";
// Version 2 adds "samples_taken": the last seq taken per source of load_samples_t. Version 1
// files (without it) are read as having taken none.
constexpr std::uint64_t kVersion = 2;

/// The checksum line's value: FNV-1a 64 (core/fnv1a.h) of every byte before it.
std::string checksum(std::string_view body) { return core::hex64(core::fnv1a64(body)); }

/// Version 1 files were checksummed by a copy of FNV-1a whose offset basis lost its last digit
/// (1469598103934665603 for 14695981039346656037); they are still read, with that value.
std::string version_one_checksum(std::string_view body) {
  std::uint64_t h = 1469598103934665603ULL;
  for (const char c : body) {
    h ^= static_cast<unsigned char>(c);
    h *= core::Fnv1a64::kPrime;
  }
  return core::hex64(h);
}

void put_block(std::string& out, const core::LoadBlock& b) {
  out += '\n';
  st::put(out, b.p_max);
  st::put(out, b.r);
  st::put(out, b.alpha);
  st::put(out, static_cast<std::uint64_t>(b.count));
}

bool read_block(st::Reader& r, core::LoadBlock& b) {
  std::uint64_t count = 0;
  const bool ok = r.number(b.p_max, "p_max") && r.number(b.r, "r") && r.number(b.alpha, "alpha") &&
                  r.count(count, "count");
  b.count = static_cast<std::int64_t>(count);
  return ok;
}

/// A saved sub-state: "<name> <bytes>\n<text>\n".
void put_text(std::string& out, std::string_view name, const std::string& text) {
  out += '\n';
  out += name;
  st::put(out, static_cast<std::uint64_t>(text.size()));
  out += '\n';
  out += text;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) {
    s.remove_suffix(1);
  }
  return s;
}

bool to_double(std::string_view s, double& v) {
  s = trim(s);
  if (s.empty()) return false;
  const std::string text(s);
  char* end = nullptr;
  errno = 0;
  v = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size();
}

}  // namespace

Pipeline::Pipeline(const config::DetailConfig& detail, const std::string& source_id,
                   loads::BatchingOptions batching, std::int64_t first_seq)
    : scale_(detail.sensor.scale),
      offset_(detail.sensor.offset),
      counter_(detail.sensor.gate),
      blocks_(loads::BlockRules{detail.sensor.alpha_bin, detail.fatigue.mirrors_compressive_cycles()}),
      batcher_(detail.id, source_id, first_seq, batching) {}

void Pipeline::emit(std::vector<messages::Batch>& out) {
  for (const auto& c : cycles_) blocks_.add(c, new_blocks_);
  cycles_.clear();
  const std::size_t before = out.size();
  for (const auto& b : new_blocks_) batcher_.add(b, out);
  new_blocks_.clear();
  for (std::size_t i = before; i < out.size(); ++i) {
    ++counts.batches;
    for (const auto& b : out[i].blocks) counts.block_cycles += static_cast<std::uint64_t>(b.count);
  }
}

void Pipeline::sample(double t, double measured, double alpha, std::vector<messages::Batch>& out) {
  ++counts.samples;
  last_time = t;
  counter_.push(scale_ * measured + offset_, alpha, cycles_);
  emit(out);
  const std::size_t before = out.size();
  batcher_.tick(t, out);
  for (std::size_t i = before; i < out.size(); ++i) {
    ++counts.batches;
    for (const auto& b : out[i].blocks) counts.block_cycles += static_cast<std::uint64_t>(b.count);
  }
}

void Pipeline::finish(loads::ResidueRule rule, std::vector<messages::Batch>& out) {
  counter_.finish(rule, cycles_);
  emit(out);
  const std::size_t before = out.size();
  batcher_.flush(out);
  for (std::size_t i = before; i < out.size(); ++i) {
    ++counts.batches;
    for (const auto& b : out[i].blocks) counts.block_cycles += static_cast<std::uint64_t>(b.count);
  }
}

std::string Pipeline::save() const {
  std::string out(kTag);
  st::put(out, kVersion);
  out += "\ncounts";
  for (const std::uint64_t v : {counts.input_lines, counts.samples, counts.bad_lines,
                                counts.batches, counts.lost_samples, counts.block_cycles}) {
    st::put(out, v);
  }
  out += "\nlast_time ";
  out += last_time ? "some" : "none";
  if (last_time) st::put(out, *last_time);
  out += "\nnext_seq";
  st::put(out, static_cast<std::uint64_t>(batcher_.next_seq()));
  out += "\nopened_at ";
  out += batcher_.opened_at() ? "some" : "none";
  if (batcher_.opened_at()) st::put(out, *batcher_.opened_at());
  out += "\nopen_blocks";
  st::put(out, static_cast<std::uint64_t>(batcher_.open_blocks().size()));
  for (const auto& b : batcher_.open_blocks()) put_block(out, b);
  out += "\nsamples_taken";
  st::put(out, static_cast<std::uint64_t>(samples_taken.size()));
  for (const auto& [source, seq] : samples_taken) {
    out += ' ';
    for (const unsigned char c : source) {  // hex: a source id may hold any byte
      constexpr char kHex[] = "0123456789abcdef";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
    st::put(out, static_cast<std::uint64_t>(seq));
  }
  put_text(out, "counter", counter_.save());
  put_text(out, "cycle_blocks", blocks_.save());
  return out;
}

namespace {
/// Reads "<name> <bytes>\n" and the text after it; advances `rest`.
bool take_text(std::string_view& rest, std::string_view name, std::string_view& text) {
  std::size_t p = 0;
  while (p < rest.size() && (rest[p] == '\n' || rest[p] == ' ')) ++p;
  rest.remove_prefix(p);
  if (!rest.starts_with(name)) return false;
  rest.remove_prefix(name.size());
  const std::size_t nl = rest.find('\n');
  if (nl == std::string_view::npos) return false;
  const std::string_view number = trim(rest.substr(0, nl));
  std::uint64_t n = 0;
  const auto r = std::from_chars(number.data(), number.data() + number.size(), n);
  if (r.ec != std::errc() || r.ptr != number.data() + number.size()) return false;
  rest.remove_prefix(nl + 1);
  if (rest.size() < n) return false;
  text = rest.substr(0, n);
  rest.remove_prefix(n);
  return true;
}
}  // namespace

core::Expected<Pipeline, std::string> Pipeline::restore(std::string_view text,
                                                        const config::DetailConfig& detail,
                                                        const std::string& source_id,
                                                        loads::BatchingOptions batching) {
  // The token part ends where the counter's text begins.
  const std::size_t counter_at = text.find("\ncounter ");
  if (counter_at == std::string_view::npos) return std::string("no counter state");
  st::Reader r(text.substr(0, counter_at), "stream state");
  std::uint64_t version = 0;
  Pipeline p(detail, source_id, batching, 1);
  r.word(kTag);
  r.count(version, "version");
  if (r.ok() && version != 1 && version != kVersion) {
    r.fail("version " + std::to_string(version) + " unknown");
  }
  r.word("counts");
  for (std::uint64_t* v : {&p.counts.input_lines, &p.counts.samples, &p.counts.bad_lines,
                           &p.counts.batches, &p.counts.lost_samples, &p.counts.block_cycles}) {
    r.count(*v, "count");
  }
  r.word("last_time");
  if (r.token("last_time") == "some") {
    double t = 0;
    r.number(t, "last_time");
    p.last_time = t;
  }
  std::uint64_t next_seq = 0, open = 0;
  r.word("next_seq");
  r.count(next_seq, "next_seq");
  std::optional<double> opened_at;
  r.word("opened_at");
  if (r.token("opened_at") == "some") {
    double t = 0;
    r.number(t, "opened_at");
    opened_at = t;
  }
  r.word("open_blocks");
  r.count(open, "open_blocks");
  std::vector<core::LoadBlock> blocks;
  for (std::uint64_t i = 0; r.ok() && i < open; ++i) {
    core::LoadBlock b;
    read_block(r, b);
    blocks.push_back(b);
  }
  std::uint64_t sources = 0;
  if (version >= 2) {
    r.word("samples_taken");
    r.count(sources, "samples_taken");
  }
  for (std::uint64_t i = 0; r.ok() && i < sources; ++i) {
    const std::string_view hex_id = r.token("source");
    std::string source;
    for (std::size_t k = 0; k + 1 < hex_id.size(); k += 2) {
      const auto digit = [](char c) {
        return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
      };
      const int hi = digit(hex_id[k]), lo = digit(hex_id[k + 1]);
      if (hi < 0 || lo < 0) break;
      source += static_cast<char>(hi * 16 + lo);
    }
    std::uint64_t seq = 0;
    r.count(seq, "seq");
    if (r.ok() && (hex_id.empty() || source.size() * 2 != hex_id.size() ||
                   source.size() > messages::kMaxSourceIdLength ||
                   seq > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()) ||
                   !p.samples_taken.emplace(source, static_cast<std::int64_t>(seq)).second)) {
      r.fail("samples_taken: bad or repeated source \"" + std::string(hex_id) + "\"");
    }
  }
  r.end();
  if (!r.ok()) return r.error();
  if (next_seq < 1) return std::string("next_seq must be >= 1");
  std::string_view rest = text.substr(counter_at);
  std::string_view counter_text, blocks_text;
  if (!take_text(rest, "counter", counter_text) || !take_text(rest, "cycle_blocks", blocks_text)) {
    return std::string("truncated counter or cycle_blocks state");
  }
  auto counter = loads::RainflowCounter::restore(counter_text);
  if (!counter) return counter.error();
  auto converter = loads::CycleBlocks::restore(blocks_text);
  if (!converter) return converter.error();
  if (counter->gate() != detail.sensor.gate ||
      converter->rules() !=
          loads::BlockRules{detail.sensor.alpha_bin, detail.fatigue.mirrors_compressive_cycles()}) {
    return std::string(
        "written with another [detail.sensor] gate / alpha_bin or compressed_bonds_fatigue");
  }
  p.counter_ = std::move(*counter);
  p.blocks_ = std::move(*converter);
  p.batcher_.restore(static_cast<std::int64_t>(next_seq), std::move(blocks), opened_at);
  return p;
}

core::Status save_state(const std::filesystem::path& file, const Pipeline& pipeline,
                        const std::vector<messages::Batch>& unacknowledged) {
  std::string text = pipeline.save();
  text += "\nunacknowledged";
  st::put(text, static_cast<std::uint64_t>(unacknowledged.size()));
  for (const auto& b : unacknowledged) {
    text += "\nbatch";
    st::put(text, static_cast<std::uint64_t>(b.seq));
    st::put(text, static_cast<std::uint64_t>(b.blocks.size()));
    for (const auto& block : b.blocks) put_block(text, block);
  }
  text += "\n";
  text += "checksum " + checksum(text) + "\n";
  const std::filesystem::path tmp = file.string() + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return core::failure(tmp.string() + ": cannot write: " + std::strerror(errno));
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = std::strerror(errno);
      ::close(fd);
      return core::failure(tmp.string() + ": write failed: " + why);
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    return core::failure(tmp.string() + ": fsync failed: " + std::strerror(errno));
  }
  if (::rename(tmp.c_str(), file.c_str()) != 0) {
    return core::failure(file.string() + ": rename failed: " + std::strerror(errno));
  }
  const auto dir = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  if (const int d = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); d >= 0) {
    ::fsync(d);
    ::close(d);
  }
  return {};
}

core::Expected<RestoredState, std::string> load_state(const std::filesystem::path& file,
                                                      const config::DetailConfig& detail,
                                                      const std::string& source_id,
                                                      loads::BatchingOptions batching) {
  const auto fail = [&](const std::string& why) { return file.string() + ": " + why; };
  std::ifstream in(file, std::ios::binary);
  if (!in) return fail("cannot open");
  std::ostringstream buf;
  buf << in.rdbuf();
  const std::string text = buf.str();
  const std::size_t at = text.rfind("checksum ");
  if (at == std::string::npos || (at > 0 && text[at - 1] != '\n')) {
    return fail("truncated (no checksum line)");
  }
  const std::string_view body(text.data(), at);
  std::string_view stored = trim(std::string_view(text).substr(at + 9));
  if (stored.ends_with('\n')) stored.remove_suffix(1);
  const bool version_one = body.starts_with(std::string(kTag) + " 1\n");
  if (stored != (version_one ? version_one_checksum(body) : checksum(body))) {
    return fail("checksum mismatch (the file was changed or is damaged)");
  }
  const std::size_t un = body.rfind("\nunacknowledged ");
  if (un == std::string_view::npos) return fail("no unacknowledged batches section");
  auto pipeline = Pipeline::restore(body.substr(0, un), detail, source_id, batching);
  if (!pipeline) return fail(pipeline.error());
  st::Reader r(body.substr(un), "unacknowledged batches");
  std::uint64_t n = 0;
  r.word("unacknowledged");
  r.count(n, "unacknowledged");
  std::vector<messages::Batch> batches;
  for (std::uint64_t i = 0; r.ok() && i < n; ++i) {
    std::uint64_t seq = 0, blocks = 0;
    r.word("batch");
    r.count(seq, "seq");
    r.count(blocks, "blocks");
    messages::Batch b{detail.id, source_id, static_cast<std::int64_t>(seq), {}};
    for (std::uint64_t k = 0; r.ok() && k < blocks; ++k) {
      core::LoadBlock block;
      read_block(r, block);
      b.blocks.push_back(block);
    }
    if (r.ok() && !batches.empty() && b.seq != batches.back().seq + 1) {
      r.fail("unacknowledged batches are not consecutive");
    }
    batches.push_back(std::move(b));
  }
  r.end();
  if (!r.ok()) return fail(r.error());
  if (!batches.empty() && batches.back().seq + 1 != pipeline->next_seq()) {
    return fail("the last unacknowledged batch is not next_seq - 1");
  }
  return RestoredState{std::move(*pipeline), std::move(batches)};
}

void write_received(const std::filesystem::path& state_file, std::uint64_t samples) {
  const std::string path = state_file.string() + ".received";
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) return;
  char buf[32];
  const int n =
      std::snprintf(buf, sizeof buf, "%020llu\n", static_cast<unsigned long long>(samples));
  if (::pwrite(fd, buf, static_cast<std::size_t>(n), 0) < 0) {
    // best effort: the count only feeds the lost_samples report
  }
  ::close(fd);
}

std::optional<std::uint64_t> read_received(const std::filesystem::path& state_file) {
  std::ifstream in(state_file.string() + ".received");
  unsigned long long v = 0;
  if (!(in >> v)) return std::nullopt;
  return static_cast<std::uint64_t>(v);
}

double sample_load_bound(const config::DetailConfig& detail) {
  return detail.limits.max_p ? *detail.limits.max_p : kAbsurdLoad;
}

ParsedLine parse_line(std::string_view line) {
  ParsedLine out;
  line = trim(line);
  if (line.starts_with("\xEF\xBB\xBF")) line = trim(line.substr(3));
  if (line.empty() || line.front() == '#') return out;
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(trim(line.substr(start, comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  if (fields.size() >= 2 && fields[0] == "time_s" && fields[1] == "load_N" &&
      (fields.size() == 2 || (fields.size() == 3 && fields[2] == "angle_rad"))) {
    return out;  // the series header
  }
  out.kind = ParsedLine::Kind::bad;
  if (fields.size() != 2 && fields.size() != 3) {
    out.why = "expected t,P or t,P,alpha (" + std::to_string(fields.size()) + " fields)";
    return out;
  }
  if (!to_double(fields[0], out.t) || !std::isfinite(out.t)) {
    out.why = "the time is not a finite number";
    return out;
  }
  if (!to_double(fields[1], out.p)) {
    out.why = "the load is not a number";
    return out;
  }
  if (fields.size() == 3 && !to_double(fields[2], out.alpha)) {
    out.why = "the angle is not a number";
    return out;
  }
  out.kind = ParsedLine::Kind::sample;
  return out;
}

}  // namespace peritwin::stream
