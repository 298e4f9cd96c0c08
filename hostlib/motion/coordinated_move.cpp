// Moves of several motors at once (coordinated_move.h).
#include "coordinated_move.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "hmc/board_frame.h"
#include "hmc/codec.h"

namespace hmc::motion::planning {

std::vector<double> Coordinator::offsets(const std::vector<Item>& items, std::vector<Command>& setup) const {
  setup.clear();
  if (options_.firmware == TargetFirmware::kV2) {
    for (const Item& it : items) {
      if (!it.planned) continue;
      setup.push_back(it.plan.set_accel());
    }
  }
  // The runner sends a line once the one before is answered (our firmware): each line costs
  // its wire time, the board's main-loop pass and its reply's wire time; a motor starts when
  // its own line has arrived and been read.
  const bool answered = options_.firmware == TargetFirmware::kV2;
  const double reply = answered ? wire_s(encode_board_frame(BoardFrame{Ack{}}).value().size() + 1, options_.baud) : 0.0;
  const double read = answered ? kBoardLoopS : 0.0;
  double t = 0;
  for (const Command& c : setup) t += wire_s(c, options_.baud) + read + reply;
  std::vector<double> out;
  for (const Item& it : items) {
    if (it.planned) {
      t += wire_s(it.plan.stm(0), options_.baud) + read;
      out.push_back(t);
      t += reply;
    } else {
      out.push_back(t);
    }
  }
  return out;
}

void Coordinator::coordinate(std::vector<Item>& items) {
  size_t moving = 0;
  for (const Item& it : items) moving += it.planned ? 1 : 0;
  if (moving < 2) return;
  double shortest_s = 1e9, longest_s = 0;
  for (const Item& it : items) {
    if (!it.planned) continue;
    for (const Piece& p : it.natural.pieces) {
      shortest_s = std::min(shortest_s, p.delay_us / 1e6);
      longest_s = std::max(longest_s, p.delay_us / 1e6);
    }
  }
  // The seed's stages follow one another by the host's clock, with a margin that grows with
  // each stage (session.h): splitting a run to end closer only moves the end by that margin,
  // so with the seed the motors end within one step period of the slowest of them.
  tolerance_s_ = std::max(kSyncToleranceS, options_.firmware == TargetFirmware::kSeed ? longest_s : shortest_s) / 2;
  std::vector<Command> setup;
  std::vector<double> off = offsets(items, setup);
  auto latest = [&] {
    double end = 0;
    for (size_t k = 0; k < items.size(); ++k) {
      if (items[k].planned) end = std::max(end, off[k] + items[k].natural.duration_s());
    }
    return end;
  };
  bool settled = false;
  for (int round = 0; round < 4 && !settled; ++round) {
    const double end = latest();
    for (size_t k = 0; k < items.size(); ++k) {
      Item& it = items[k];
      if (!it.planned || fit_item(it, end - off[k], 0, 0)) continue;
      const double need = end - off[k];
      const bool too_few = need > static_cast<double>(it.natural.steps) * kMaxDelayUs / 1e6;
      error(it.where, "a move that can be slowed to " + num(need) + " s", profile_words(it.move->profile),
            it.config->name + " cannot be slowed to arrive with the other motors: it would have to take " + num(need) +
                " s" + (too_few ? ", and " + std::to_string(it.natural.steps) + " steps take at most 89 s each" : ""));
      it.planned = false;
    }
    std::vector<double> again = offsets(items, setup);
    settled = again == off;
    off = std::move(again);
  }
  if (settled) return;
  double end = 0;
  for (size_t k = 0; k < items.size(); ++k) {
    if (items[k].planned) end = std::max(end, off[k] + items[k].plan.duration_s());
  }
  for (size_t k = 0; k < items.size(); ++k) {
    Item& it = items[k];
    if (it.planned && std::fabs(off[k] + it.plan.duration_s() - end) > tolerance_s_) refit_tail(it, end - off[k]);
  }
}

bool Coordinator::fit_item(Item& it, double target_s, size_t stm_chars, size_t set_chars) const {
  const double own = it.natural.duration_s();
  auto lines_ok = [&](const MotorPlan& p) {
    return (stm_chars == 0 || chars(p.stm(0)) == stm_chars) && (set_chars == 0 || chars(p.set_accel()) == set_chars);
  };
  if (target_s <= own + 1e-9 && lines_ok(it.natural)) {
    it.plan = it.natural;
    return true;
  }
  for (Shape shape : {Shape::kAsked, Shape::kStaircase, Shape::kConstant}) {
    for (bool keep_first : {false, true}) {
      const Fit fit{target_s, shape, keep_first, stm_chars, set_chars, tolerance_s_};
      Result<MotorPlan, Problem> p = plan_motor(*it.move, *it.config, it.natural.steps, it.natural.dir, it.natural.link,
                                                std::max(1.0, target_s / own), &fit);
      if (p.ok()) {
        it.plan = p.value();
        return true;
      }
    }
  }
  return false;
}

bool Coordinator::refit_tail(Item& it, double target_s) const {
  MotorPlan p = it.plan;
  const bool v2 = options_.firmware == TargetFirmware::kV2;
  if (p.firmware_ramp) return fit_item(it, target_s, chars(p.stm(0)), v2 ? chars(p.set_accel()) : 0);
  std::vector<Piece> tail(p.pieces.begin() + 1, p.pieces.end());
  p.pieces.resize(1);
  if (tail.empty()) {  // one run: split off a head whose line is as long as the whole run's
    const size_t want = chars(p.stm(0));
    const uint64_t n = p.pieces[0].steps;
    for (uint64_t h = n - 1; h >= 1 && n - h <= 2000 && tail.empty(); --h) {
      p.pieces[0].steps = h;
      if (chars(p.stm(0)) == want) tail.push_back({n - h, p.pieces[0].delay_us});
    }
    if (tail.empty()) return false;
  }
  p.pieces.insert(p.pieces.end(), tail.begin(), tail.end());
  fit_with_gaps(p, 1, static_cast<double>(p.pieces[0].steps) * p.pieces[0].delay_us, target_s, false, tolerance_s_);
  if (check_rates(p, it.config->name) || std::fabs(p.duration_s() - target_s) > tolerance_s_) return false;
  it.plan = p;
  return true;
}

}  // namespace hmc::motion::planning
