// OpenHaptics (HD API) implementation of the vendor driver skeleton. Compiled only with
// -DTELEOP_WITH_VENDOR_SDK=ON (client/CMakeLists.txt finds HD/hd.h and libHD). CI compiles and
// runs it against a simulated device behind a stand-in of the HD API subset it calls
// (tests/vendor/vendor_sdk_test.cpp); it has not met the real SDK or a real device: check it on
// the hardware before trusting it.
#include "client/device/vendor/vendor_sdk_device.hpp"

#include <HD/hd.h>

#include <cmath>

#include "common/config/config.hpp"

namespace teleop::master {

namespace {

HDCallbackCode HDCALLBACK servo_callback(void* self) {
  return static_cast<VendorSdkDevice*>(self)->servo_tick() ? HD_CALLBACK_CONTINUE
                                                           : HD_CALLBACK_DONE;
}

// hdGetError() pops the SDK's error stack: read it once and describe what was read
std::string hd_error_text(const HDErrorInfo& e) {
  return HD_DEVICE_ERROR(e)
             ? std::string(reinterpret_cast<const char*>(hdGetErrorString(e.errorCode)))
             : std::string("no error");
}

}  // namespace

VendorSdkDevice::VendorSdkDevice(std::string device_name) : device_name_(std::move(device_name)) {}

VendorSdkDevice::~VendorSdkDevice() {
  deactivate();
  if (state_ != DeviceLifecycle::kUnconfigured) hdDisableDevice(static_cast<HHD>(handle_));
}

void VendorSdkDevice::configure() {
  const HHD h = hdInitDevice(device_name_.empty() ? HD_DEFAULT_DEVICE : device_name_.c_str());
  if (const HDErrorInfo e = hdGetError(); HD_DEVICE_ERROR(e)) {
    throw config::ConfigError("--device vendor: cannot open the device: " + hd_error_text(e));
  }
  handle_ = static_cast<unsigned long>(h);
  hdMakeCurrentDevice(h);
  // the device declares its spec; the SDK speaks millimetres and N/mm
  HDdouble ws[6] = {};  // usable workspace box: minX, minY, minZ, maxX, maxY, maxZ [mm]
  hdGetDoublev(HD_USABLE_WORKSPACE_DIMENSIONS, ws);
  HDdouble max_force = 0, max_cont = 0, max_k = 0, max_b = 0;
  hdGetDoublev(HD_NOMINAL_MAX_FORCE, &max_force);
  hdGetDoublev(HD_NOMINAL_MAX_CONTINUOUS_FORCE, &max_cont);
  hdGetDoublev(HD_NOMINAL_MAX_STIFFNESS, &max_k);  // N/mm
  hdGetDoublev(HD_NOMINAL_MAX_DAMPING, &max_b);    // N s/mm
  spec_.name =
      std::string("vendor: ") + reinterpret_cast<const char*>(hdGetString(HD_DEVICE_MODEL_TYPE));
  spec_.workspace_min_m = Eigen::Vector3d(ws[0], ws[1], ws[2]) * 1e-3;
  spec_.workspace_max_m = Eigen::Vector3d(ws[3], ws[4], ws[5]) * 1e-3;
  spec_.max_force_n = max_force;
  spec_.max_continuous_force_n = max_cont;
  spec_.max_stiffness_n_per_m = max_k * 1e3;
  spec_.max_damping_ns_per_m = max_b * 1e3;
  spec_.max_torque_nm = 0.0;  // set if the model has actuated gimbal torques
  spec_.translational_dof = 3;
  spec_.rotational_dof = 3;
  state_ = DeviceLifecycle::kInactive;
}

void VendorSdkDevice::activate() {
  if (state_ == DeviceLifecycle::kUnconfigured) configure();
  if (state_ == DeviceLifecycle::kActive) return;
  hdEnable(HD_FORCE_OUTPUT);
  callback_ = static_cast<unsigned long>(
      hdScheduleAsynchronous(servo_callback, this, HD_MAX_SCHEDULER_PRIORITY));
  hdStartScheduler();
  if (const HDErrorInfo e = hdGetError(); HD_DEVICE_ERROR(e)) {
    throw config::ConfigError("--device vendor: cannot start the servo loop: " + hd_error_text(e));
  }
  state_ = DeviceLifecycle::kActive;
}

void VendorSdkDevice::deactivate() {
  if (state_ != DeviceLifecycle::kActive) return;
  exchange_.command.store(vendor::ServoCommand{});  // zero force on the next tick
  hdStopScheduler();
  hdUnschedule(static_cast<HDSchedulerHandle>(callback_));
  hdDisable(HD_FORCE_OUTPUT);
  state_ = DeviceLifecycle::kInactive;
}

bool VendorSdkDevice::servo_tick() {
  hdBeginFrame(static_cast<HHD>(handle_));
  vendor::ServoReading r;
  HDdouble p[3], v[3], t[16];
  HDint buttons = 0;
  hdGetDoublev(HD_CURRENT_POSITION, p);   // mm
  hdGetDoublev(HD_CURRENT_VELOCITY, v);   // mm/s
  hdGetDoublev(HD_CURRENT_TRANSFORM, t);  // column-major 4x4
  hdGetIntegerv(HD_CURRENT_BUTTONS, &buttons);
  for (int i = 0; i < 3; ++i) {
    r.position_m[i] = p[i] * 1e-3;
    r.velocity_mps[i] = v[i] * 1e-3;
  }
  const Eigen::Matrix3d R = Eigen::Map<const Eigen::Matrix4d>(t).topLeftCorner<3, 3>();
  const Eigen::Quaterniond q(R);
  r.orientation_wxyz[0] = q.w();
  r.orientation_wxyz[1] = q.x();
  r.orientation_wxyz[2] = q.y();
  r.orientation_wxyz[3] = q.z();
  r.buttons = static_cast<std::uint32_t>(buttons);
  vendor::ServoCommand c;
  const std::uint32_t stored = exchange_.command.load(c);
  servo_stale_ticks_ = stored != servo_seen_ ? 0 : servo_stale_ticks_ + 1;
  servo_seen_ = stored;
  Eigen::Vector3d f(c.force_n[0], c.force_n[1], c.force_n[2]);
  // a stalled haptic loop: fade out; otherwise the newest force within the spec
  f = servo_stale_ticks_ < kServoStaleTicks ? saturate_norm(f, spec_.max_force_n)
                                            : Eigen::Vector3d::Zero();
  const Eigen::Vector3d delta = f - servo_force_n_;
  const double step = spec_.max_force_rate_n_per_s * kServoPeriodS;
  if (step > 0.0 && delta.norm() > step) f = servo_force_n_ + delta * (step / delta.norm());
  if (!c.enable) f.setZero();  // switched off (deactivate): at once, the output is disabled too
  servo_force_n_ = f;
  const HDdouble out[3] = {f.x(), f.y(), f.z()};
  hdSetDoublev(HD_CURRENT_FORCE, out);
  hdEndFrame(static_cast<HHD>(handle_));
  r.fault = HD_DEVICE_ERROR(hdGetError());
  exchange_.reading.store(r);
  return true;
}

DeviceReading VendorSdkDevice::read() {
  DeviceReading out;
  vendor::ServoReading r;
  if (state_ != DeviceLifecycle::kActive || exchange_.reading.load(r) == 0 || r.fault) return out;
  out.time_s = time_s_;
  out.position_m = Eigen::Vector3d(r.position_m[0], r.position_m[1], r.position_m[2]);
  out.linear_velocity_mps =
      Eigen::Vector3d(r.velocity_mps[0], r.velocity_mps[1], r.velocity_mps[2]);
  out.orientation = Eigen::Quaterniond(r.orientation_wxyz[0], r.orientation_wxyz[1],
                                       r.orientation_wxyz[2], r.orientation_wxyz[3]);
  out.buttons = r.buttons;
  out.valid = true;
  return out;
}

void VendorSdkDevice::write(const Eigen::Vector3d& force_n, const Eigen::Vector3d& torque_nm) {
  vendor::ServoCommand c;
  const Eigen::Vector3d f = saturate_norm(force_n, spec_.max_force_n);
  const Eigen::Vector3d t = saturate_norm(torque_nm, spec_.max_torque_nm);
  for (int i = 0; i < 3; ++i) {
    c.force_n[i] = f[i];
    c.torque_nm[i] = t[i];
  }
  c.enable = state_ == DeviceLifecycle::kActive;
  exchange_.command.store(c);
}

void VendorSdkDevice::advance(double dt_s) { time_s_ += dt_s; }

std::unique_ptr<HapticDevice> make_vendor_sdk_device(const std::string& device_name) {
  return std::make_unique<VendorSdkDevice>(device_name);
}

}  // namespace teleop::master
