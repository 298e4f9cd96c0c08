// hmc-emu-bench: runs a bare-metal benchmark program on hmc-emu's CPU. The program is bench/qemu's
// (built for qemu's microbit machine: flash at 0x0, RAM at 0x20000000, SysTick, semihosting for
// its output and exit), clocked as `qemu-system-arm -icount shift=10` clocks it: one instruction
// per 1024 ns of virtual time, SysTick at 16 MHz, so 16.384 SysTick ticks per instruction. The
// instruction counts it prints must then equal qemu's, row for row: the calibration of hmc-emu's
// CPU against qemu (emu/tests/calibration_test.sh, docs/performance.md).
//
// Exit status: the program's (0 when it exits with ADP_Stopped_ApplicationExit, 1 otherwise);
// 2 bad usage, 3 the ELF cannot be read, 5 the program broke a rule of the emulated chip or
// ran past --max-instructions.
//
// --cycles charges the cycle model's cycles (DDI0484C table 3-1, flash wait states as the
// program leaves NVMCTRL: none at reset) instead of one per instruction: the program's
// "instructions" then read as cycles (fill()'s cost per ramp step, docs/performance.md).
#include <CLI/CLI.hpp>
#include <cinttypes>
#include <cstdio>
#include <iostream>

#include "chip/chip.h"
#include "chip/scs.h"
#include "cpu/cpu.h"
#include "elf/elf_image.h"

int main(int argc, char** argv) {
  std::string path;
  uint64_t max_instructions = 2000000000;
  CLI::App app{"hmc-emu-bench: runs bench/qemu's program on hmc-emu's CPU with qemu's instruction clock"};
  app.add_option("image", path, "the benchmark ELF (build/qemu/bench.elf)")->required();
  app.add_option("--max-instructions", max_instructions, "stop as an error after this many instructions");
  bool cycles = false;
  app.add_flag("--cycles", cycles, "clock by the cycle model: the figures printed are cycles");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  using namespace hmc::emu;
  ElfImage image;
  std::string error;
  if (!load_elf(path, image, error)) {
    std::cerr << "hmc-emu-bench: " << error << '\n';
    return 3;
  }
  ChipOptions chip_options;
  chip_options.after_bootloader = false;
  Chip chip(chip_options);
  chip.scs().set_systick_rate(16384, 1000);
  CpuOptions cpu_options;
  cpu_options.cost = cycles ? CostModel::kCycles : CostModel::kInstructions;
  cpu_options.semihosting = true;
  Cpu cpu(chip, image, cpu_options);
  if (!cpu.init(error) || !cpu.reset(0, error)) {
    std::cerr << "hmc-emu-bench: " << error << '\n';
    return 3;
  }
  while (!cpu.exited() && !chip.stopped() && cpu.instructions() < max_instructions) {
    cpu.run_until(chip.now_ps() + Chip::kPsPerSecond / 10);
    std::cout << cpu.take_semihost_output() << std::flush;
  }
  if (!cpu.exited()) {
    std::cerr << "hmc-emu-bench: stopped after " << cpu.instructions() << " instructions: "
              << (chip.stopped() ? chip.violation_message() : "--max-instructions reached")
              << "\nhmc-emu-bench: PC in " << cpu.where(cpu.pc()) << '\n';
    return 5;
  }
  std::fprintf(stderr, "hmc-emu-bench: %" PRIu64 " instructions, program exit %s\n",
               cpu.instructions(), cpu.exit_ok() ? "ok" : "failed");
  return cpu.exit_ok() ? 0 : 1;
}
