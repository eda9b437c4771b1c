// libFuzzer target for the checkpoint reader (io/checkpoint_file.hpp, core/state_archive.hpp;
// see fuzz/README.md).
//
// Each input is a checkpoint file. It is verified (header, size, CRC-32) and parsed into records
// exactly as `lamina run --restart` does; every record is then read with every accessor, and the
// state is restored into a small PD explicit, PD quasi-static and MPM analysis (the cases of
// fuzz/checkpoint/), as the restart does after the case check. libFuzzer finds inputs that pass
// the checksum by itself only rarely, so inputs that fail it are retried once with the checksum
// fixed up: the record parser and the restore code are fuzzed, not only the CRC.
//
// Expected outcome: success or lamina::StateError (a refused checkpoint: exit 2 in the program).
// Anything else - another exception, a crash, a sanitizer report - is a finding: abort.
#include <zlib.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "app/model.hpp"
#include "app/run_command.hpp"
#include "core/error.hpp"
#include "core/state_archive.hpp"
#include "io/checkpoint_file.hpp"

#ifndef LAMINA_FUZZ_CHECKPOINT_CASES
#error "LAMINA_FUZZ_CHECKPOINT_CASES (the folder of the analyses' case files) must be defined"
#endif

namespace {

struct Target {
  lamina::app::PreparedCase prepared;
  lamina::app::Model model;
};

std::vector<Target>& targets() {
  static std::vector<Target> all = [] {
    std::vector<Target> list;
    for (const char* name : {"pd_explicit.yaml", "pd_quasi_static.yaml", "mpm_strip.yaml"}) {
      Target t;
      t.prepared = lamina::app::prepare_case(std::string(LAMINA_FUZZ_CHECKPOINT_CASES) + "/" + name, {});
      t.model = lamina::app::build_point_model(t.prepared.case_data);
      list.push_back(std::move(t));
    }
    return list;
  }();
  return all;
}

void read_every_record(const lamina::StateReader& in) {
  for (const auto& name : in.names()) {
    auto quietly = [](auto&& read) {
      try {
        read();
      } catch (const lamina::StateError&) {
      }
    };
    quietly([&] { (void)in.real(name); });
    quietly([&] { (void)in.integer(name); });
    quietly([&] { (void)in.text(name); });
    quietly([&] { (void)in.reals(name); });
    quietly([&] { (void)in.integers(name); });
    quietly([&] { (void)in.ints(name); });
    quietly([&] { (void)in.matrix(name); });
    quietly([&] {
      Eigen::Matrix3Xd m(3, 4);
      in.matrix_into(name, m);
    });
  }
}

void exercise(const std::vector<char>& file) {
  std::vector<char> payload;
  try {
    payload = lamina::io::parse_checkpoint(file);
  } catch (const lamina::StateError&) {
    return;
  }
  std::unique_ptr<lamina::StateReader> in;
  try {
    in = std::make_unique<lamina::StateReader>(std::move(payload));
  } catch (const lamina::StateError&) {
    return;
  }
  read_every_record(*in);
  for (auto& t : targets()) {
    auto analysis = t.prepared.method->create(t.prepared.case_data, t.model, *t.prepared.options);
    try {
      analysis->restore_state(*in);
    } catch (const lamina::StateError&) {
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    std::vector<char> file(reinterpret_cast<const char*>(data), reinterpret_cast<const char*>(data) + size);
    exercise(file);
    // the same bytes with a valid checksum (header layout: io/checkpoint_file.cpp)
    if (file.size() >= 32) {
      const std::uint64_t payload = file.size() - 32;
      std::memcpy(file.data() + 16, &payload, 8);
      const std::uint32_t crc = static_cast<std::uint32_t>(
          crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(file.data() + 32), static_cast<uInt>(payload)));
      std::memcpy(file.data() + 24, &crc, 4);
      exercise(file);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "checkpoint_reader_fuzzer: unexpected exception: %s\n", e.what());
    std::abort();
  }
  return 0;
}
