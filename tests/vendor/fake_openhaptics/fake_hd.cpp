// A simulated OpenHaptics device behind the HD API subset of include/HD/hd.h: a scheduler thread
// runs the scheduled callbacks at 1 kHz; frames read the handle the test set and record the
// force the driver wrote. Written for this project's tests.
#include "fake_hd.hpp"

#include <HD/hd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <mutex>
#include <thread>
#include <vector>

namespace {

struct Scheduled {
  HDSchedulerCallback callback;
  void* data;
  HDSchedulerHandle handle;
  bool done;
};

struct State {
  std::mutex m;
  fake_hd::Declared declared;
  bool fail_init = false;
  bool fault = false;
  bool open = false;
  bool force_output = false;
  HDerror error = HD_SUCCESS;
  double position_mm[3] = {0, 0, 0};
  double velocity_mm_s[3] = {0, 0, 0};
  int buttons = 0;
  double force_n[3] = {0, 0, 0};
  std::vector<Scheduled> scheduled;
  HDSchedulerHandle next_handle = 1;
  std::atomic<bool> running{false};
  std::atomic<std::uint64_t> ticks{0};
  std::thread thread;
};

State& st() {
  static State s;
  return s;
}

void run_scheduler() {
  State& s = st();
  auto next = std::chrono::steady_clock::now();
  while (s.running.load()) {
    std::vector<Scheduled> now;
    {
      std::lock_guard<std::mutex> l(s.m);
      now = s.scheduled;
    }
    for (auto& c : now) {
      if (c.done) continue;
      if (c.callback(c.data) == HD_CALLBACK_DONE) {
        std::lock_guard<std::mutex> l(s.m);
        for (auto& k : s.scheduled)
          if (k.handle == c.handle) k.done = true;
      }
    }
    s.ticks.fetch_add(1);
    next += std::chrono::milliseconds(1);
    std::this_thread::sleep_until(next);
  }
}

}  // namespace

namespace fake_hd {

void reset(const Declared& d) {
  State& s = st();
  if (s.running.load()) hdStopScheduler();
  std::lock_guard<std::mutex> l(s.m);
  s.declared = d;
  s.fail_init = false;
  s.fault = false;
  s.open = false;
  s.force_output = false;
  s.error = HD_SUCCESS;
  std::memset(s.position_mm, 0, sizeof(s.position_mm));
  std::memset(s.velocity_mm_s, 0, sizeof(s.velocity_mm_s));
  s.buttons = 0;
  std::memset(s.force_n, 0, sizeof(s.force_n));
  s.scheduled.clear();
  s.ticks = 0;
}
void fail_next_init() {
  std::lock_guard<std::mutex> l(st().m);
  st().fail_init = true;
}
void set_fault(bool on) {
  std::lock_guard<std::mutex> l(st().m);
  st().fault = on;
}
void set_handle(const double p[3], const double v[3], int buttons) {
  std::lock_guard<std::mutex> l(st().m);
  for (int i = 0; i < 3; ++i) {
    st().position_mm[i] = p[i];
    st().velocity_mm_s[i] = v[i];
  }
  st().buttons = buttons;
}
void last_force(double f[3], bool& enabled) {
  std::lock_guard<std::mutex> l(st().m);
  for (int i = 0; i < 3; ++i) f[i] = st().force_n[i];
  enabled = st().force_output;
}
std::uint64_t ticks() { return st().ticks.load(); }
bool scheduler_running() { return st().running.load(); }

}  // namespace fake_hd

extern "C" {

HHD hdInitDevice(HDstring) {
  State& s = st();
  std::lock_guard<std::mutex> l(s.m);
  if (s.fail_init) {
    s.fail_init = false;
    s.error = HD_INVALID_HANDLE;
    return HD_INVALID_HANDLE_VALUE;
  }
  s.error = HD_SUCCESS;
  s.open = true;
  return 1;
}
void hdDisableDevice(HHD) {
  std::lock_guard<std::mutex> l(st().m);
  st().open = false;
}
void hdMakeCurrentDevice(HHD) {}
HDErrorInfo hdGetError(void) {
  State& s = st();
  std::lock_guard<std::mutex> l(s.m);
  HDErrorInfo e{s.error, 0, 1};
  s.error = HD_SUCCESS;  // the SDK pops errors off a stack
  return e;
}
HDstring hdGetErrorString(HDerror code) {
  return code == HD_INVALID_HANDLE ? "no device found (fake)"
         : code == HD_DEVICE_FAULT ? "device fault (fake)"
                                   : "no error";
}
void hdGetDoublev(HDenum name, HDdouble* v) {
  State& s = st();
  std::lock_guard<std::mutex> l(s.m);
  const fake_hd::Declared& d = s.declared;
  switch (name) {
    case HD_USABLE_WORKSPACE_DIMENSIONS:
      for (int i = 0; i < 6; ++i) v[i] = d.workspace_mm[i];
      break;
    case HD_NOMINAL_MAX_FORCE:
      v[0] = d.max_force_n;
      break;
    case HD_NOMINAL_MAX_CONTINUOUS_FORCE:
      v[0] = d.max_continuous_force_n;
      break;
    case HD_NOMINAL_MAX_STIFFNESS:
      v[0] = d.max_stiffness_n_per_mm;
      break;
    case HD_NOMINAL_MAX_DAMPING:
      v[0] = d.max_damping_ns_per_mm;
      break;
    case HD_CURRENT_POSITION:
      for (int i = 0; i < 3; ++i) v[i] = s.position_mm[i];
      break;
    case HD_CURRENT_VELOCITY:
      for (int i = 0; i < 3; ++i) v[i] = s.velocity_mm_s[i];
      break;
    case HD_CURRENT_TRANSFORM:  // column-major 4x4: identity rotation, the handle's position
      for (int i = 0; i < 16; ++i) v[i] = (i % 5 == 0) ? 1.0 : 0.0;
      for (int i = 0; i < 3; ++i) v[12 + i] = s.position_mm[i];
      break;
    default:
      break;
  }
}
void hdGetIntegerv(HDenum name, HDint* v) {
  std::lock_guard<std::mutex> l(st().m);
  if (name == HD_CURRENT_BUTTONS) v[0] = st().buttons;
}
HDstring hdGetString(HDenum name) {
  return name == HD_DEVICE_MODEL_TYPE ? st().declared.model : "";
}
void hdSetDoublev(HDenum name, const HDdouble* v) {
  std::lock_guard<std::mutex> l(st().m);
  if (name == HD_CURRENT_FORCE) {
    for (int i = 0; i < 3; ++i) st().force_n[i] = v[i];
  }
}
void hdEnable(HDenum cap) {
  std::lock_guard<std::mutex> l(st().m);
  if (cap == HD_FORCE_OUTPUT) st().force_output = true;
}
void hdDisable(HDenum cap) {
  std::lock_guard<std::mutex> l(st().m);
  if (cap == HD_FORCE_OUTPUT) {
    st().force_output = false;
    for (double& f : st().force_n) f = 0.0;
  }
}
void hdBeginFrame(HHD) {}
void hdEndFrame(HHD) {
  std::lock_guard<std::mutex> l(st().m);
  if (st().fault) st().error = HD_DEVICE_FAULT;
}
HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback cb, void* data, HDushort) {
  std::lock_guard<std::mutex> l(st().m);
  const HDSchedulerHandle h = st().next_handle++;
  st().scheduled.push_back(Scheduled{cb, data, h, false});
  return h;
}
void hdUnschedule(HDSchedulerHandle h) {
  std::lock_guard<std::mutex> l(st().m);
  auto& v = st().scheduled;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (v[i].handle == h) {
      v.erase(v.begin() + static_cast<long>(i));
      break;
    }
  }
}
void hdStartScheduler(void) {
  State& s = st();
  if (s.running.exchange(true)) return;
  s.thread = std::thread(run_scheduler);
}
void hdStopScheduler(void) {
  State& s = st();
  if (!s.running.exchange(false)) return;
  if (s.thread.joinable()) s.thread.join();
}

}  // extern "C"
