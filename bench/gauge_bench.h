// peritwin-bench stream --gauges: the rate of stream::LoadIdentifier::identify (strain gauges ->
// P, α; stream/gauge_identification.h), in-process, no daemon.
#pragma once

#include <cstdint>

namespace peritwin::bench {
/// For 8 gauges in each form of the load (p_only, linear_pair, constant_and_angle): `samples`
/// identify() calls, without and with the residuals, on 4096 precomputed noisy samples used in
/// turn (P = 2200 + 1800 sin, α a slow sine, 1 to 2.75 µε of normal noise, fixed seed); one JSON
/// line per form: samples/s and their ratio to issue 33's goal of 10 kHz on one core, and the
/// RMS error of P against the truth; and the same for the stream's whole per-sample path
/// (stream_path_*: the text line parsed by stream::GaugeFeed, identified, its compliance window
/// summed, then rainflow, blocks and batches by stream::Pipeline; only file reading and sending
/// left out). Returns the exit code.
int run_gauge_identification(std::int64_t samples);
}  // namespace peritwin::bench
