#include "common/util/rate_loop.hpp"

#include <sys/prctl.h>
#include <time.h>

#include <cmath>
#include <stdexcept>

#include "common/util/clock.hpp"

namespace teleop {

RateLoop::RateLoop(double rate_hz, std::size_t jitter_capacity, std::int64_t spin_ns)
    : period_ns_(0), next_ns_(0), spin_ns_(spin_ns), lateness_us_(jitter_capacity) {
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) {
    throw std::invalid_argument("RateLoop: rate_hz must be a positive finite number");
  }
  period_ns_ = static_cast<std::int64_t>(std::llround(1e9 / rate_hz));
  if (spin_ns < 0 || spin_ns >= period_ns_) {
    throw std::invalid_argument("RateLoop: spin_ns must be in [0, period)");
  }
  // the default 50 us timer slack of a normal thread would show up as wake-up jitter
  prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  reset();
}

void RateLoop::reset() { next_ns_ = now_ns() + period_ns_; }

namespace {

void sleep_until(std::int64_t t_ns) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t_ns / 1000000000LL);
  ts.tv_nsec = static_cast<long>(t_ns % 1000000000LL);
  // steady_clock is CLOCK_MONOTONIC on Linux
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) != 0) {
  }
}

}  // namespace

void RateLoop::sleep_until_lead(std::int64_t lead_ns) {
  const std::int64_t wake_ns = next_ns_ - lead_ns;
  if (now_ns() < wake_ns) sleep_until(wake_ns);
}

bool RateLoop::wait() {
  ++iterations_;
  std::int64_t now = now_ns();
  bool on_time = true;
  if (now > next_ns_) {
    // missed: count the whole periods lost and re-anchor on the next boundary
    const std::int64_t missed = (now - next_ns_) / period_ns_ + 1;
    overruns_ += static_cast<std::uint64_t>(missed);
    next_ns_ += missed * period_ns_;
    on_time = false;
  }
  const std::int64_t wake_ns = next_ns_ - spin_ns_;
  if (now < wake_ns) sleep_until(wake_ns);
  now = now_ns();
  while (now < next_ns_) now = now_ns();
  lateness_us_.record(static_cast<double>(now - next_ns_) * 1e-3);
  next_ns_ += period_ns_;
  return on_time;
}

}  // namespace teleop
