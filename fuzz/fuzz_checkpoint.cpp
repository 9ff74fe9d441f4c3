// libFuzzer target for the checkpoint loader (scripts/fuzz.sh runs it; issue 16).
//
// An input is a checkpoint payload: the target puts the header in front of it (magic, format
// version, size and the right FNV-1a hash), so that the fuzzer reaches the payload decoder
// instead of stopping at the checksum. Inputs starting with 'H' go to the decoder as they are
// (the header checks themselves); inputs starting with 'P' are the payload of a distributed
// checkpoint's piece (io::decode_piece). Invalid input must be reported as an InputError; any other
// exception, a crash, a sanitizer report or an allocation beyond libFuzzer's limit is a bug.
// A payload that decodes must encode to the same bytes, and what a restart does with it next
// (the particles unpacked in each dimension, the FEM state, the stored configuration compared
// with itself) must again end in an InputError or succeed.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>

#include "core/bytes.hpp"
#include "core/types.hpp"
#include "io/checkpoint.hpp"

namespace {

[[noreturn]] void bug(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_checkpoint: %s: %s\n", what, detail.c_str());
  std::abort();
}

template <class Fn>
void may_refuse(Fn&& f) {
  try {
    f();
  } catch (const mpm::InputError&) {
  }
}

void fuzz(std::string_view bytes) {
  namespace io = mpm::io;
  io::Checkpoint c;
  try {
    c = io::decode_checkpoint(bytes, "<fuzz>");
  } catch (const mpm::InputError&) {
    return;
  }
  if (io::encode_checkpoint(c) != bytes) bug("decode then encode changes the bytes", "");
  may_refuse([&] { (void)io::unpack_particles<1>(c.particles, "<fuzz>"); });
  may_refuse([&] { (void)io::unpack_particles<2>(c.particles, "<fuzz>"); });
  may_refuse([&] { (void)io::unpack_particles<3>(c.particles, "<fuzz>"); });
  if (c.fem) may_refuse([&] { (void)io::unpack_fem(*c.fem, "<fuzz>"); });
  may_refuse([&] { (void)io::restart_config(c, "<fuzz>", nullptr); });
}

// A piece must encode back to its bytes, and its particles unpack or are refused.
void fuzz_piece(std::string_view payload) {
  namespace io = mpm::io;
  mpm::ByteWriter w;
  w.bytes().append(io::kPieceMagic);
  w.u32(io::kCheckpointVersion);
  w.u64(payload.size());
  w.u64(io::fnv1a64(payload));
  w.bytes().append(payload);
  io::CheckpointPiece p;
  try {
    p = io::decode_piece(w.bytes(), "<fuzz piece>");
  } catch (const mpm::InputError&) {
    return;
  }
  if (io::encode_piece(p) != w.bytes()) bug("piece: decode then encode changes the bytes", "");
  may_refuse([&] { (void)io::unpack_particles<2>(p.particles, "<fuzz piece>"); });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  try {
    if (!input.empty() && input.front() == 'H') {
      fuzz(input.substr(1));
    } else if (!input.empty() && input.front() == 'P') {
      fuzz_piece(input.substr(1));
    } else {
      mpm::ByteWriter w;
      w.bytes().append(mpm::io::kCheckpointMagic);
      w.u32(mpm::io::kCheckpointVersion);
      w.u64(input.size());
      w.u64(mpm::io::fnv1a64(input));
      w.bytes().append(input);
      fuzz(w.bytes());
    }
  } catch (const std::exception& e) {
    bug("exception other than mpm::InputError", e.what());
  } catch (...) {
    bug("exception other than mpm::InputError", "(not a std::exception)");
  }
  return 0;
}
