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
/// prewarm are checked against the period after the parse, where the rate is known, and the CPU
/// against the core count.
inline void add_realtime_flags(CLI::App& app, RealtimeOptions& rt, const std::string& loop,
                               const std::string& period, bool prewarm) {
  add_integer(app, "--realtime", rt.priority, 0.0, 99.0,
              "run the " + loop + " SCHED_FIFO at this priority (0 = a normal thread)");
  add_integer(app, "--cpu", rt.cpu, -1.0, 4096.0,
              "pin the " + loop + " to this CPU, below the core count (-1 = no pinning)");
  add_integer(app, "--spin-us", rt.spin_us, 0.0, 1e5,
              "busy-wait this long before each " + period +
                  "'s deadline, below the period (0 = sleep to it)",
              "us");
  if (prewarm) {
    add_integer(app, "--prewarm-us", rt.prewarm_us, 0.0, 1e5,
                "read the next " + period +
                    "'s data into the caches during this long before each deadline, below the "
                    "period (0 = no)",
                "us");
  }
  add_integer(app, "--nice", rt.nice, -20.0, 19.0,
              "the " + loop + "'s nice value as a normal thread (0 = unchanged)");
  app.add_flag("--lock-memory", rt.lock_memory,
               "lock every page of the process in memory (mlockall, present and future) and "
               "pre-fault the loop's stack");
  add_integer(app, "--dma-latency-us", rt.dma_latency_us, -1.0, 1e5,
              "hold /dev/cpu_dma_latency at this value while running (-1 = no)", "us");
}

}  // namespace teleop::config
