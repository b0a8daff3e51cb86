#pragma once
// The scheduling flags of a 1 kHz loop (common/util/realtime.hpp), declared once for the
// server's physics loop and the master's haptic loop (header-only: the apps link CLI11).
#include <CLI/CLI.hpp>

#include <string>

#include "common/config/flags.hpp"
#include "common/util/realtime.hpp"

namespace teleop::config {

/// Adds --realtime, --cpu, --spin-us, --prewarm-us (only where `prewarm`), --nice,
/// --lock-memory and --dma-latency-us to `app`, writing into `rt`. `loop` names the loop in the
/// help ("physics loop"), `period` one of its periods ("step", "cycle"). The spin and the
/// prewarm are checked against the period after the parse, where the rate is known.
inline void add_realtime_flags(CLI::App& app, RealtimeOptions& rt, const std::string& loop,
                               const std::string& period, bool prewarm) {
  app.add_option("--realtime", rt.priority,
                 "run the " + loop + " SCHED_FIFO at this priority, 1-99 (0 = a normal thread)")
      ->check(integer_in(0.0, 99.0));
  app.add_option("--cpu", rt.cpu, "pin the " + loop + " to this CPU (-1 = no pinning)")
      ->check(integer_in(-1.0, 4096.0));
  app.add_option("--spin-us", rt.spin_us,
                 "busy-wait this long before each " + period +
                     "'s deadline [us], 0 to the period (0 = sleep to it)")
      ->check(integer_in(0.0, 1e5));
  if (prewarm) {
    app.add_option("--prewarm-us", rt.prewarm_us,
                   "read the next " + period +
                       "'s data into the caches during this long before each deadline [us], 0 "
                       "to the period (0 = no)")
        ->check(integer_in(0.0, 1e5));
  }
  app.add_option("--nice", rt.nice,
                 "the " + loop + "'s nice value as a normal thread, -20 to 19 (0 = unchanged)")
      ->check(integer_in(-20.0, 19.0));
  app.add_flag("--lock-memory", rt.lock_memory,
               "lock every page of the process in memory (mlockall, present and future) and "
               "pre-fault the loop's stack");
  app.add_option("--dma-latency-us", rt.dma_latency_us,
                 "hold /dev/cpu_dma_latency at this value while running [us] (-1 = no)")
      ->check(integer_in(-1.0, 1e5));
}

}  // namespace teleop::config
