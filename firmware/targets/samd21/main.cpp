// The SAMD21 firmware's entry: wires the board's HAL objects (this directory) into fw::Board,
// runs the Controller, and routes the interrupts the firmware uses.
//
//   irq_tc4      motor 1's step compare (and the step clock), priority 0 → the step engine's
//   irq_tcc1     motor 2's step compare, priority 0                       lanes
//   irq_tcc2     motor 3's step compare, priority 0                       (step_fast_path.h), in RAM
//   irq_sercom5  command UART, priority 1 → receive ring / transmit ring
//   irq_eic      switches, priority 2     → Controller::on_switch_change()
//
// Order at power-up: interrupts masked (reset_handler masks them first; anything a bootloader
// enabled is switched off here), clocks (48 MHz), watchdog, every output to its safe level,
// peripherals, interrupts on, then at least 1 ms before the drivers are configured (the DRV8711
// accepts SPI 1 ms after power-up, HARDWARE.md), Controller::boot() with the reset cause, and
// the main loop.
#include "board.h"
#include "boot_leds.h"
#include "buzzer.h"
#include "clocks.h"
#include "core/controller.h"
#include "dma.h"
#include "irq.h"
#include "led_strips.h"
#include "reset_cause.h"
#include "serial_port.h"
#include "servo_pwm.h"
#include "spi_bus.h"
#include "step_fast_path.h"
#include "step_pins.h"
#include "step_timer.h"
#include "switches.h"
#include "watchdog.h"

namespace {

using namespace hmc;

samd21::StepTimer step_timer;
samd21::StepPins step_pins;
samd21::SpiBus spi_bus;
samd21::ServoPwm servo_pwm;
samd21::LedStrips led_strips;
samd21::Switches switches;
samd21::Buzzer buzzer(step_timer);
samd21::BootLeds boot_leds;
samd21::SerialPort serial_port;

const fw::Board board{step_timer, step_pins, spi_bus,   servo_pwm,  led_strips,
                      switches,   buzzer,    boot_leds, serial_port};
fw::Controller controller(board, fw::ControllerOptions{});

static_assert(samd21::board::uart::kSercom == 5, "irq_sercom5 below serves the command UART");

constexpr hal::Ticks kDriverPowerUpTicks = hal::kTicksPerSecond / 1000u;  // 1 ms

// Which clock the DFLL locked to, for a debugger (nothing on the wire reports it).
volatile samd21::ClockSource clock_source;

}  // namespace

// In RAM (.ramfunc, samd21_sections.ld): no flash wait states on the step path. -O2 here (the
// rest is -Os): the common path then branches less and spills less (one motor: 205 cycles a step
// against 222 at -Os when it was set, scripts/bench cycles), for ≈ 1 KiB more RAM code.
// Each lane's full entry, called when its express entry declines (GCC ignores a section on a
// template function: these are not templates).
__attribute__((section(".ramfunc.step_general_1"), noinline, optimize("O2"))) void step_general_1() {
  samd21::run_step_general<0>(step_timer, controller.step_engine());
}
__attribute__((section(".ramfunc.step_general_2"), noinline, optimize("O2"))) void step_general_2() {
  samd21::run_step_general<1>(step_timer, controller.step_engine());
}
__attribute__((section(".ramfunc.step_general_3"), noinline, optimize("O2"))) void step_general_3() {
  samd21::run_step_general<2>(step_timer, controller.step_engine());
}

extern "C" __attribute__((section(".ramfunc.irq_tc4"), optimize("O2"))) void irq_tc4() {
  if (!samd21::run_step_express<0>(step_timer, controller.step_engine())) step_general_1();
}

extern "C" __attribute__((section(".ramfunc.irq_tcc1"), optimize("O2"))) void irq_tcc1() {
  if (!samd21::run_step_express<1>(step_timer, controller.step_engine())) step_general_2();
}

extern "C" __attribute__((section(".ramfunc.irq_tcc2"), optimize("O2"))) void irq_tcc2() {
  if (!samd21::run_step_express<2>(step_timer, controller.step_engine())) step_general_3();
}

extern "C" void irq_sercom5() { serial_port.on_interrupt(); }

extern "C" void irq_eic() {
  switches.take_interrupt();
  controller.on_switch_change();
}

int main() {
  samd21::irq_quiesce();
  clock_source = samd21::clocks_init();
  samd21::watchdog_start();

  step_pins.init();  // STEP, DIR low; chip selects inactive (low)
  samd21::dma_init();  // the STEP pulses' channels (step_timer) and the LED strips'
  step_timer.start();  // counting from here: the 1 ms wait below includes the set-up
  boot_leds.init();
  buzzer.init();
  servo_pwm.init();
  spi_bus.init();
  led_strips.init();
  serial_port.init();
  switches.init();
  samd21::irq_enable_all();

  while (step_timer.now() < kDriverPowerUpTicks) samd21::watchdog_kick();
  controller.boot(samd21::reset_report_take());

  for (;;) {
    controller.poll();
    led_strips.service();
    servo_pwm.service();
    buzzer.service();
    samd21::watchdog_kick();
  }
}
