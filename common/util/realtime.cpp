#include "common/util/realtime.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace teleop {
namespace {

/// Writes every page of a stack frame this large, so the loop's deeper calls find their stack
/// pages present (with MCL_FUTURE they then stay).
[[gnu::noinline]] void prefault_stack() {
  constexpr std::size_t kBytes = 256 * 1024;
  [[maybe_unused]] volatile unsigned char frame[kBytes];
  for (std::size_t i = 0; i < kBytes; i += 4096) frame[i] = 0;
}

}  // namespace

DmaLatencyHold::DmaLatencyHold(int latency_us) {
  if (latency_us < 0) return;
  fd_ = ::open("/dev/cpu_dma_latency", O_WRONLY | O_CLOEXEC);
  if (fd_ < 0) {
    problem_ = std::string("/dev/cpu_dma_latency: ") + std::strerror(errno);
    return;
  }
  // the device takes a binary 32-bit value
  const std::int32_t v = latency_us;
  if (::write(fd_, &v, sizeof(v)) != static_cast<ssize_t>(sizeof(v))) {
    problem_ = std::string("/dev/cpu_dma_latency: writing ") + std::to_string(latency_us) + ": " +
               std::strerror(errno);
    ::close(fd_);
    fd_ = -1;
  }
}

DmaLatencyHold::~DmaLatencyHold() {
  if (fd_ >= 0) ::close(fd_);
}

DmaLatencyHold::DmaLatencyHold(DmaLatencyHold&& o) noexcept
    : fd_(o.fd_), problem_(std::move(o.problem_)) {
  o.fd_ = -1;
}

DmaLatencyHold& DmaLatencyHold::operator=(DmaLatencyHold&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = o.fd_;
    problem_ = std::move(o.problem_);
    o.fd_ = -1;
  }
  return *this;
}

std::string make_thread_realtime(const RealtimeOptions& o) {
  std::string problems;
  if (o.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(o.cpu, &set);
    if (const int e = pthread_setaffinity_np(pthread_self(), sizeof(set), &set); e != 0) {
      problems += "pinning to CPU " + std::to_string(o.cpu) + ": " + std::strerror(e) + "; ";
    }
  }
  if (o.lock_memory) {
    // every page, present and future, stays in memory; the stack is faulted in first
    if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
      problems += std::string("locking memory: ") + std::strerror(errno) +
                  " (needs root or CAP_IPC_LOCK, or a large enough `ulimit -l`); ";
    }
    prefault_stack();
  }
  if (o.nice != 0 && o.priority == 0) {
    // Linux: the nice value of one thread (its kernel task id)
    if (setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), o.nice) != 0) {
      problems += "nice " + std::to_string(o.nice) + ": " + std::strerror(errno) +
                  " (a negative value needs root or CAP_SYS_NICE); ";
    }
  }
  if (o.priority > 0) {
    // the pages touched so far (the loop's preallocated state) stay in memory: no page fault
    // in the loop; later allocations (other threads) are not locked
    if (!o.lock_memory && mlockall(MCL_CURRENT) != 0) {
      problems += std::string("locking memory: ") + std::strerror(errno) + "; ";
    }
    sched_param p{};
    p.sched_priority = o.priority;
    if (const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p); e != 0) {
      problems += "SCHED_FIFO priority " + std::to_string(o.priority) + ": " + std::strerror(e) +
                  " (needs root or CAP_SYS_NICE, and an RT budget: "
                  "/proc/sys/kernel/sched_rt_runtime_us)";
    }
  }
  if (problems.size() >= 2 && problems.substr(problems.size() - 2) == "; ") {
    problems.resize(problems.size() - 2);
  }
  return problems;
}

}  // namespace teleop
