// Fuzz target: the input as a checkpoint file -> read_checkpoint (HDF5 from a temp file; HDF5
// itself is not instrumented). Properties: the data or a CheckpointError naming the file; never
// a crash, another exception, or an allocation the file cannot justify (ASan, libFuzzer's
// -malloc_limit_mb).
#include "outputs/checkpoint_io.h"
#include "tests/fuzz/fuzz_target.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using peritwin::fuzz::require;
  static peritwin::fuzz::TempFile file(".h5");
  const auto& path = file.write(data, size);
  try {
    (void)peritwin::outputs::read_checkpoint(path);
  } catch (const peritwin::outputs::CheckpointError& e) {
    const std::string m = e.what();
    require(m.find(path.string()) != std::string::npos, "the error names the file");
  }
  return 0;
}
