// teleop_viewer: a 3-D observer of a running session. Subscribes only (it never writes), so any
// number may join or leave at any time; the latched topics (scene, mesh topology, events) bring a
// late joiner up to date.
//
//   teleop_viewer [--domain D] [--profile P] [--width 1280] [--height 720] [--fps 0]
//                 [--history 10] [--duration S] [--full-rate]
//   teleop_viewer --domain D --snapshot out.png [--after 2.0] [--timeout 30]     (headless)
//
// Window: the scene (planes, deformable meshes, robot skeleton, tip, contact force arrow) on the
// left, plots and events on the right. Headless (--snapshot): a hidden window and an offscreen
// framebuffer; once the scene, a slave state and every mesh have arrived it waits --after seconds
// of live data, renders, writes a PNG and exits. Needs an X display: under Xvfb for tests and
// documentation (xvfb-run -a -s "-screen 0 1280x720x24" teleop_viewer ...).
//
// Topics: by default the 60 Hz copies of the state (teleop/slave_state_view,
// teleop/master_state_view, written off the loops' threads) and the mesh frames (60 Hz), so any
// number of viewers costs the 1 kHz loops nothing; --full-rate reads the 1 kHz topics.
//
// Threads: one DDS reader thread per topic copies each sample into ViewerData (short mutex, no
// allocation after warm-up); the render loop copies what changed once per frame and draws at the
// display rate (vsync) or --fps.
//
// Drive (--drive, docs/tools.md "Drive it by hand"): the viewer is also the master's haptic
// device (teleop/device_state at 1 kHz from a 1 kHz thread; teleop_master --device external)
// and its tuning tool (teleop/tuning; teleop_master --accept-tuning). Drag the ring at the
// master's hand with the left button, or hold the arrows and PgUp/PgDn; the force the master
// renders is drawn as an arrow from the ring and as a bar. --input-script FILE plays the same
// input from a file (client/viewer/input_script.hpp), through the same handlers.
//
// Exit status: 0 done, 1 runtime failure (no display, OpenGL, DDS, file), 2 bad command line,
// 3 snapshot: the data never became complete within --timeout.
#include <sys/resource.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "client/viewer/gl/gl_api.hpp"
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include "client/viewer/camera.hpp"
#include "client/viewer/drive_session.hpp"
#include "client/viewer/gl/offscreen.hpp"
#include "client/viewer/gl/renderer.hpp"
#include "client/viewer/input_script.hpp"
#include "client/viewer/png.hpp"
#include "client/viewer/ui/drive_panel.hpp"
#include "client/viewer/ui/panel.hpp"
#include "client/viewer/viewer_data.hpp"
#include "common/config/config.hpp"
#include "common/config/flags.hpp"
#include "common/dds/endpoint.hpp"
#include "common/dds/guid_text.hpp"
#include "common/dds/network_flags.hpp"
#include "common/dds/observer_topics.hpp"
#include "common/util/clock.hpp"
#include "common/util/files.hpp"
#include "common/util/signals.hpp"
#include "common/util/stats.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace {

using namespace teleop;
using viewer::ViewerData;
using viewer::ViewerView;

constexpr int kExitRuntime = 1;
constexpr int kExitUsage = 2;
constexpr int kExitNoData = 3;

struct Options {
  std::optional<int> domain;
  std::optional<std::string> profile;
  std::string snapshot;  ///< headless: write this PNG and exit
  double after_s = 2.0;
  double timeout_s = 30.0;
  int width = 1280;
  int height = 720;
  double fps = 0.0;  ///< 0: the display rate (vsync)
  double history_s = 10.0;
  double duration_s = 0.0;
  std::optional<int> msaa;  ///< default: 4, or 0 in a window on a software renderer
  double force_scale_m_per_n = 0.25;
  double displacement_scale_m = 0.003;
  int nice = 19;  ///< scheduling priority of every viewer thread (0 normal, 19 lowest)
  bool hide_panel = false;
  bool wireframe = false;
  bool plain_colours = false;  ///< start without the displacement colours (key C)
  bool full_rate = false;      ///< read the 1 kHz topics instead of the 60 Hz *_view copies
  // drive
  bool drive = false;                ///< be the master's device and tuning tool
  std::string input_script;          ///< scripted input (needs --drive)
  std::string drive_json;            ///< write the drive summary here at exit
  double drive_scale = 1.0;          ///< slave metres per device metre (the master's alpha)
  double drive_peak_force_n = 10.0;  ///< declared peak force of the device [N]
};

/// Checks the flags that CLI11 cannot; throws config::ConfigError naming flag, value and range.
void validate(const Options& o) {
  using config::check_flag;
  check_flag("--after", o.after_s, 0.0, 3600.0);
  check_flag("--timeout", o.timeout_s, 0.1, 3600.0);
  check_flag("--width", o.width, 320, 7680);
  check_flag("--height", o.height, 240, 4320);
  check_flag("--fps", o.fps, 0.0, 1000.0);
  check_flag("--history", o.history_s, 1.0, 600.0);
  check_flag("--duration", o.duration_s, 0.0, 1e7);
  if (o.msaa) check_flag("--msaa", *o.msaa, 0, 16);
  check_flag("--nice", o.nice, 0, 19);
  check_flag("--force-scale", o.force_scale_m_per_n, 1e-4, 10.0);
  check_flag("--displacement-scale", o.displacement_scale_m, 1e-5, 1.0);
  check_flag("--drive-scale", o.drive_scale, 1e-3, 1e3);
  check_flag("--drive-peak-force", o.drive_peak_force_n, 0.1, 1000.0);
  if (!o.drive && (!o.input_script.empty() || !o.drive_json.empty())) {
    throw config::ConfigError("command line: --input-script and --drive-json need --drive");
  }
  if (o.drive && !o.snapshot.empty()) {
    throw config::ConfigError("command line: --drive needs a window; it cannot go with --snapshot");
  }
  if (!o.snapshot.empty()) {
    const std::filesystem::path p(o.snapshot);
    std::string ext = p.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext != ".png") {
      throw config::ConfigError("command line: --snapshot " + o.snapshot +
                                ": the file name must end in .png");
    }
    const std::filesystem::path dir = p.has_parent_path() ? p.parent_path() : ".";
    if (!std::filesystem::is_directory(dir)) {
      throw config::ConfigError("command line: --snapshot " + o.snapshot + ": the directory " +
                                dir.string() + " does not exist");
    }
  }
}

double ms_between(std::int64_t a_ns, std::int64_t b_ns) {
  return static_cast<double>(b_ns - a_ns) * 1e-6;
}

class ViewerApp {
 public:
  ViewerApp(const Options& options, const teleop::dds::ParticipantOptions& dds_options)
      : options_(options),
        dds_options_(dds_options),
        headless_(!options.snapshot.empty()),
        t0_ns_(now_ns()),
        data_(options.history_s, t0_ns_),
        frame_ms_(1 << 14) {
    render_options_.wireframe = options.wireframe;
    render_options_.displacement_colors = !options.plain_colours;
    render_options_.displacement_scale_m = static_cast<float>(options.displacement_scale_m);
    render_options_.force_scale_m_per_n = static_cast<float>(options.force_scale_m_per_n);
    show_panel_ = !options.hide_panel;
    panel_info_.domain = dds_options.domain;
    panel_info_.profile =
        dds_options.profile + (dds_options.insecure ? " INSECURE (no DDS Security)" : "");
    panel_info_.history_s = options.history_s;
    frame_scratch_.reserve(frame_ms_.capacity());
  }

  ~ViewerApp() { shutdown(); }
  ViewerApp(const ViewerApp&) = delete;
  ViewerApp& operator=(const ViewerApp&) = delete;

  /// Window, OpenGL, ImGui and the renderer. Returns an exit status, or 0 on success.
  int init_graphics() {
    glfwSetErrorCallback([](int code, const char* text) {
      std::cerr << "teleop_viewer: GLFW error " << code << ": " << text << "\n";
    });
    if (!glfwInit()) {
      std::cerr << "teleop_viewer: cannot open a window: no usable X display (DISPLAY='"
                << (std::getenv("DISPLAY") ? std::getenv("DISPLAY") : "")
                << "'). Run it on a desktop, over ssh -X, or headless with xvfb-run "
                   "(see docs/viewer.md).\n";
      return kExitRuntime;
    }
    glfw_ready_ = true;
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_SAMPLES, 0);  // anti-aliasing happens offscreen (OffscreenTarget)
    glfwWindowHint(GLFW_VISIBLE, headless_ ? GLFW_FALSE : GLFW_TRUE);
    const std::string title = "teleop_viewer - domain " + std::to_string(dds_options_.domain);
    // headless: a small hidden window only carries the context; pictures go to a framebuffer
    window_ = glfwCreateWindow(headless_ ? 64 : options_.width, headless_ ? 64 : options_.height,
                               title.c_str(), nullptr, nullptr);
    if (!window_) {
      std::cerr << "teleop_viewer: cannot create an OpenGL 3.3 core window (on a remote X "
                   "display try LIBGL_ALWAYS_SOFTWARE=1; see docs/viewer.md)\n";
      return kExitRuntime;
    }
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(options_.fps > 0.0 ? 0 : 1);
    renderer_name_ = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    gl_version_ = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    // multisampling costs a software renderer several times the frame time: a window there
    // goes without unless asked; a snapshot is one frame and gets it
    software_ = renderer_name_.find("llvmpipe") != std::string::npos ||
                renderer_name_.find("softpipe") != std::string::npos ||
                renderer_name_.find("swrast") != std::string::npos;
    msaa_ = options_.msaa.value_or(headless_ || !software_ ? 4 : 0);

    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini next to the user's files
    ImGui::StyleColorsDark();
    ImGui::GetStyle().WindowRounding = 0.0f;
    ImGui_ImplGlfw_InitForOpenGL(window_, true);
    ImGui_ImplOpenGL3_Init("#version 330 core");
    imgui_ready_ = true;

    std::string error;
    if (!renderer_.init(error)) {
      std::cerr << "teleop_viewer: " << error << "\n";
      return kExitRuntime;
    }
    std::cerr << "teleop_viewer: OpenGL " << gl_version_ << " on " << renderer_name_ << ", "
              << msaa_ << "x MSAA, domain " << dds_options_.domain << ", profile "
              << dds_options_.profile
              << (headless_ ? ", headless snapshot to " + options_.snapshot : std::string())
              << "\n";
    return 0;
  }

  /// Creates the participant and one reader per topic.
  void init_dds() {
    using eprosima::fastdds::dds::SampleInfo;
    participant_ = std::make_unique<teleop::dds::Participant>(dds_options_);
    auto& p = *participant_;
    r_scene_ = std::make_unique<teleop::dds::Reader<SceneDescriptionPubSubType>>(
        p, teleop::dds::topics::kScene,
        [this](const SceneDescription& s, const SampleInfo&) { data_.on_scene(s); });
    r_topology_ = std::make_unique<teleop::dds::Reader<MeshTopologyPubSubType>>(
        p, teleop::dds::topics::kMeshTopology,
        [this](const MeshTopology& t, const SampleInfo&) { data_.on_topology(t); });
    const teleop::dds::ObserverTopics topics =
        teleop::dds::observer_topics(teleop::dds::ObserverKind::kView, options_.full_rate);
    r_frames_ = std::make_unique<teleop::dds::Reader<MeshFramePubSubType>>(
        p, topics.mesh_frame,
        [this](const MeshFrame& f, const SampleInfo&) { data_.on_mesh_frame(f); });
    r_slave_ = std::make_unique<teleop::dds::Reader<SlaveStatePubSubType>>(
        p, topics.slave_state, [this](const SlaveState& s, const SampleInfo& info) {
          note_server(info, true);
          data_.on_slave_state(s, now_ns());
        });
    r_master_ = std::make_unique<teleop::dds::Reader<MasterStatePubSubType>>(
        p, topics.master_state,
        [this](const MasterState& s, const SampleInfo&) { data_.on_master_state(s, now_ns()); });
    r_stats_ = std::make_unique<teleop::dds::Reader<ServerStatsPubSubType>>(
        p, teleop::dds::topics::kServerStats, [this](const ServerStats& s, const SampleInfo& info) {
          note_server(info, false);
          data_.on_server_stats(s, now_ns());
        });
    r_events_ = std::make_unique<teleop::dds::Reader<EventPubSubType>>(
        p, teleop::dds::topics::kEvents,
        [this](const Event& e, const SampleInfo&) { data_.on_event(e, now_ns()); });
    r_experiment_ = std::make_unique<teleop::dds::Reader<ExperimentDescriptionPubSubType>>(
        p, teleop::dds::topics::kExperiment,
        [this](const ExperimentDescription& e, const SampleInfo&) { data_.on_experiment(e); });
    if (options_.drive) {
      viewer::HandDriveParams hp;
      hp.position_scale = options_.drive_scale;
      drive_ = std::make_unique<viewer::DriveSession>(p, hp, options_.drive_peak_force_n);
    }
  }

  void set_script(std::vector<viewer::ScriptAction> script) { script_ = std::move(script); }

  /// The render loop. Returns the exit status.
  int run() {
    // --fps, else the display's vsync. A software renderer is slow enough at 1280x720 that a
    // low frame rate leaves the CPU to the control loops (docs/viewer.md, "Measured"). Headless
    // runs only lay out the UI until the snapshot: 30 fps.
    double period_s = options_.fps > 0.0 ? 1.0 / options_.fps
                      : headless_        ? 1.0 / 30.0
                      : software_        ? 1.0 / 15.0
                                         : 0.0;
    std::int64_t next_frame_ns = now_ns();
    std::int64_t ready_ns = 0;
    int frames_since_ready = 0;
    std::int64_t first_frame_ns = 0;
    while (true) {
      glfwPollEvents();
      if (stop_requested() || glfwWindowShouldClose(window_)) break;
      const std::int64_t frame_start = now_ns();
      if (first_frame_ns == 0) first_frame_ns = frame_start;
      const double elapsed_s = seconds_between(t0_ns_, frame_start);
      if (options_.duration_s > 0.0 && elapsed_s >= options_.duration_s) break;

      if (!paused_) data_.update(view_);
      renderer_.sync_scene(view_);
      if (view_.have_scene()) renderer_.upload_deformables(view_, render_options_);
      update_rates(frame_start);
      if (drive_ && !run_script(frame_start)) break;

      // headless: wait until the data is complete, then --after seconds more
      bool snapshot_now = false;
      if (headless_) {
        if (ready_ns == 0 && view_.complete()) {
          ready_ns = frame_start;
          std::cerr << "teleop_viewer: data complete after " << elapsed_s << " s (scene '"
                    << view_.scene.name() << "'), snapshot in " << options_.after_s << " s\n";
        }
        if (ready_ns != 0) {
          ++frames_since_ready;
          snapshot_now = seconds_between(ready_ns, frame_start) >= options_.after_s &&
                         frames_since_ready >= 3;  // ImGui lays windows out over a frame or two
        } else if (elapsed_s > options_.timeout_s) {
          std::cerr << "teleop_viewer: no complete data on domain " << dds_options_.domain
                    << " within --timeout " << options_.timeout_s
                    << " s (missing: " << view_.missing()
                    << "). Is a teleop_server running on this domain and "
                    << "profile?\n";
          return kExitNoData;
        }
      }

      // headless: the frames before the snapshot only lay the UI out; only the last one is drawn
      const int status = draw_frame(!headless_ || snapshot_now, snapshot_now);
      if (status >= 0) return status;

      const std::int64_t frame_end = now_ns();
      frame_ms_.record(ms_between(frame_start, frame_end));
      ++frames_;
      // vsync requested but the display does not throttle: pace at its refresh rate ourselves
      if (period_s == 0.0 && frames_ == 120) {
        const double measured_hz = 119.0 / seconds_between(first_frame_ns, frame_end);
        const double display_hz = display_refresh_hz();
        if (measured_hz > 1.25 * display_hz) {
          period_s = 1.0 / display_hz;
          std::cerr << "teleop_viewer: the display does not throttle (" << measured_hz
                    << " fps; no vsync, e.g. Xvfb or a remote X server): pacing at " << display_hz
                    << " fps (--fps to choose)\n";
        }
      }
      if (period_s > 0.0) {
        next_frame_ns += static_cast<std::int64_t>(period_s * 1e9);
        if (next_frame_ns < frame_end) next_frame_ns = frame_end;  // late: do not catch up
        std::this_thread::sleep_for(std::chrono::nanoseconds(next_frame_ns - now_ns()));
      }
    }
    return 0;
  }

  /// Prints the frame statistics.
  void print_summary() const {
    if (frames_ == 0 || headless_) return;  // headless frames only lay out the UI
    std::vector<double> ms = frame_ms_.snapshot();
    const Summary s = summarize(ms);
    const double span_s = seconds_between(t0_ns_, now_ns());
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    const double cpu_s =
        static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
        1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
    std::printf(
        "teleop_viewer: %llu frames in %.1f s (%.1f fps); frame time (update + draw + swap) "
        "p50 %.2f ms, p99 %.2f ms, max %.2f ms; CPU %.1f ms per frame (all threads, %.0f%% of a "
        "core); %dx%d, %dx MSAA, %s\n",
        static_cast<unsigned long long>(frames_), span_s, static_cast<double>(frames_) / span_s,
        s.p50, s.p99, s.max, 1e3 * cpu_s / static_cast<double>(frames_), 100.0 * cpu_s / span_s,
        target_.width(), target_.height(), msaa_, renderer_name_.c_str());
    std::fflush(stdout);
  }

 private:
  /// Refresh rate of the primary monitor [Hz], 60 when unknown.
  static double display_refresh_hz() {
    GLFWmonitor* monitor = glfwGetPrimaryMonitor();
    const GLFWvidmode* mode = monitor ? glfwGetVideoMode(monitor) : nullptr;
    return (mode && mode->refreshRate > 0) ? mode->refreshRate : 60.0;
  }

  /// Builds the UI and, when `render` is set, draws one frame (and writes the snapshot when
  /// `snapshot` is set). Returns -1 to go on, else an exit status.
  int draw_frame(bool render, bool snapshot) {
    int win_w = options_.width, win_h = options_.height, fb_w = win_w, fb_h = win_h;
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGuiIO& io = ImGui::GetIO();
    if (headless_) {
      io.DisplaySize = ImVec2(static_cast<float>(win_w), static_cast<float>(win_h));
      io.DisplayFramebufferScale = ImVec2(1.0f, 1.0f);
      io.MousePos = ImVec2(-FLT_MAX, -FLT_MAX);
    } else {
      glfwGetWindowSize(window_, &win_w, &win_h);
      glfwGetFramebufferSize(window_, &fb_w, &fb_h);
    }
    ImGui::NewFrame();
    const bool minimised = win_w <= 0 || win_h <= 0 || fb_w <= 0 || fb_h <= 0;
    const viewer::Layout layout =
        viewer::layout_for(std::max(win_w, 1), std::max(win_h, 1), show_panel_);
    if (!headless_ && !minimised) handle_input(layout);
    panel_info_.now_s = seconds_between(t0_ns_, now_ns());
    panel_info_.paused = paused_;
    panel_info_.wireframe = render_options_.wireframe;
    panel_info_.displacement_colors = render_options_.displacement_colors;
    panel_info_.robot_status = robot_status();
    panel_info_.max_displacement_m = renderer_.max_displacement_m();
    panel_info_.headless = headless_;
    panel_info_.width = fb_w;
    panel_info_.height = fb_h;
    panel_info_.msaa = msaa_;
    viewer::draw_panel(view_, panel_info_, layout);
    viewer::draw_overlay(view_, panel_info_);
    if (drive_) draw_drive(layout);
    ImGui::Render();
    if (!render || minimised) return -1;

    // everything is drawn offscreen (anti-aliased), then shown or saved
    if (target_.width() != fb_w || target_.height() != fb_h) {
      std::string error;
      if (!target_.create(fb_w, fb_h, msaa_, error)) {
        std::cerr << "teleop_viewer: " << error << "\n";
        return kExitRuntime;
      }
    }
    target_.bind();
    glViewport(0, 0, fb_w, fb_h);
    glClearColor(0.08f, 0.08f, 0.10f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    const float scale = static_cast<float>(fb_w) / static_cast<float>(win_w);
    const int view_w = static_cast<int>(static_cast<float>(layout.view_width) * scale + 0.5f);
    renderer_.draw(view_, camera_, render_options_, 0, 0, view_w, fb_h);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());

    if (headless_) return snapshot ? write_snapshot() : -1;
    if (save_requested_) {
      save_requested_ = false;
      save_window();
    }
    target_.present();
    glfwSwapBuffers(window_);
    return -1;
  }

  int write_snapshot() {
    viewer::Image image;
    target_.read(image);
    std::string error;
    if (!viewer::write_png_file(options_.snapshot, image, error)) {
      std::cerr << "teleop_viewer: " << error << "\n";
      return kExitRuntime;
    }
    std::cerr << "teleop_viewer: wrote " << options_.snapshot << " (" << image.width << "x"
              << image.height << ")\n";
    return 0;
  }

  void save_window() {
    char name[64];
    const std::time_t t = std::time(nullptr);
    std::strftime(name, sizeof(name), "teleop_viewer_%Y%m%d_%H%M%S.png", std::localtime(&t));
    const std::string file = save_path_.empty() ? std::string(name) : save_path_;
    save_path_.clear();
    viewer::Image image;
    target_.read(image);
    target_.bind();
    std::string error;
    panel_info_.note =
        viewer::write_png_file(file, image, error) ? "saved " + file : "save failed: " + error;
    std::cerr << "teleop_viewer: " << panel_info_.note << "\n";
  }

  void handle_input(const viewer::Layout& layout) {
    const ImGuiIO& io = ImGui::GetIO();
    if (!io.WantCaptureKeyboard) {
      if (ImGui::IsKeyPressed(GLFW_KEY_R, false)) camera_ = viewer::OrbitCamera{};
      if (ImGui::IsKeyPressed(GLFW_KEY_W, false)) {
        render_options_.wireframe = !render_options_.wireframe;
      }
      if (ImGui::IsKeyPressed(GLFW_KEY_C, false)) {
        render_options_.displacement_colors = !render_options_.displacement_colors;
      }
      if (ImGui::IsKeyPressed(GLFW_KEY_F, false)) {
        render_options_.show_force = !render_options_.show_force;
      }
      if (ImGui::IsKeyPressed(GLFW_KEY_H, false)) show_panel_ = !show_panel_;
      if (ImGui::IsKeyPressed(GLFW_KEY_P, false) || ImGui::IsKeyPressed(GLFW_KEY_SPACE, false)) {
        paused_ = !paused_;
      }
      if (ImGui::IsKeyPressed(GLFW_KEY_S, false)) save_requested_ = true;
      if (ImGui::IsKeyPressed(GLFW_KEY_Q, false) || ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false)) {
        glfwSetWindowShouldClose(window_, GLFW_TRUE);
      }
    }
    if (drive_) {
      drive_keys(io.DeltaTime);
      const Eigen::Vector2f mouse(io.MousePos.x, io.MousePos.y);
      if (mouse_dragging_) {
        if (ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
          drive_move(mouse, layout);
        } else {
          drive_->release();
          mouse_dragging_ = false;
        }
        return;
      }
      if (!io.WantCaptureMouse && !script_dragging_ &&
          ImGui::IsMouseClicked(ImGuiMouseButton_Left) && !io.KeyShift &&
          drive_press(mouse, layout)) {
        mouse_dragging_ = true;
        return;
      }
    }
    if (io.WantCaptureMouse || io.MousePos.x >= static_cast<float>(layout.view_width)) return;
    const bool pan = ImGui::IsMouseDown(ImGuiMouseButton_Right) ||
                     ImGui::IsMouseDown(ImGuiMouseButton_Middle) ||
                     (ImGui::IsMouseDown(ImGuiMouseButton_Left) && io.KeyShift);
    if (pan) {
      camera_.pan(io.MouseDelta.x, io.MouseDelta.y, static_cast<float>(layout.view_height));
    } else if (ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
      camera_.orbit(io.MouseDelta.x, io.MouseDelta.y);
    }
    if (io.MouseWheel != 0.0f) camera_.zoom(io.MouseWheel);
  }

  // ---- drive (--drive) ----

  /// The master's hand in the slave world (MasterState.command_position_m); false until known.
  bool hand_world(Eigen::Vector3d& hand) const {
    if (!view_.have_master) return false;
    const auto& p = view_.master.command_position_m();
    hand = Eigen::Vector3d(p[0], p[1], p[2]);
    return hand.allFinite() && hand.squaredNorm() > 0.0;
  }

  void pixel_ray(const Eigen::Vector2f& px, const viewer::Layout& layout, Eigen::Vector3d& o,
                 Eigen::Vector3d& d) const {
    Eigen::Vector3f of, df;
    camera_.ray(px, static_cast<float>(layout.view_width), static_cast<float>(layout.view_height),
                of, df);
    o = of.cast<double>();
    d = df.cast<double>();
  }

  /// A left press at `px`: grabs the hand when the press is within 30 px of its ring.
  bool drive_press(const Eigen::Vector2f& px, const viewer::Layout& layout) {
    Eigen::Vector3d hand;
    if (!hand_world(hand)) return false;
    Eigen::Vector2f at;
    if (!camera_.project(hand.cast<float>(), static_cast<float>(layout.view_width),
                         static_cast<float>(layout.view_height), at) ||
        (at - px).norm() > 30.0f) {
      return false;
    }
    Eigen::Vector3d o, d;
    pixel_ray(px, layout, o, d);
    drive_->grab(hand, camera_.forward().cast<double>(), o, d);
    return drive_->dragging();
  }

  void drive_move(const Eigen::Vector2f& px, const viewer::Layout& layout) {
    Eigen::Vector3d o, d;
    pixel_ray(px, layout, o, d);
    drive_->drag(o, d);
  }

  /// Held arrows and PgUp/PgDn move the hand along the world axes.
  void drive_keys(float dt_s) {
    if (ImGui::GetIO().WantCaptureKeyboard) return;
    Eigen::Vector3d dir = Eigen::Vector3d::Zero();
    if (ImGui::IsKeyDown(ImGuiKey_RightArrow)) dir.x() += 1.0;
    if (ImGui::IsKeyDown(ImGuiKey_LeftArrow)) dir.x() -= 1.0;
    if (ImGui::IsKeyDown(ImGuiKey_UpArrow)) dir.y() += 1.0;
    if (ImGui::IsKeyDown(ImGuiKey_DownArrow)) dir.y() -= 1.0;
    if (ImGui::IsKeyDown(ImGuiKey_PageUp)) dir.z() += 1.0;
    if (ImGui::IsKeyDown(ImGuiKey_PageDown)) dir.z() -= 1.0;
    drive_->nudge(dir, dt_s);
  }

  void send_tuning(std::uint32_t fields) {
    drive_->send_tuning(viewer::make_tuning_request(tuning_form_, fields));
  }

  void draw_drive(const viewer::Layout& layout) {
    const viewer::DriveView v = drive_->view();
    Eigen::Vector3d hand;
    if (hand_world(hand)) {
      viewer::draw_drive_overlay(camera_, static_cast<float>(layout.view_width),
                                 static_cast<float>(layout.view_height), hand, v,
                                 options_.force_scale_m_per_n, drive_->dragging());
    }
    const std::uint32_t fields = viewer::draw_drive_window(v, drive_->peak_force_n(), tuning_form_,
                                                           static_cast<float>(layout.view_height));
    if (fields != 0) send_tuning(fields);
  }

  /// Plays --input-script through the handlers above. Returns false to close the viewer.
  bool run_script(std::int64_t now) {
    if (script_.empty() && !script_dragging_ && script_key_until_s_ < 0.0) return true;
    Eigen::Vector3d hand;
    if (script_t0_ns_ == 0) {
      if (!hand_world(hand)) return true;  // times count from when the hand is known
      script_t0_ns_ = now;
      std::cerr << "teleop_viewer: input script starts (the master's hand is known)\n";
    }
    const double t = seconds_between(script_t0_ns_, now);
    const viewer::Layout layout = viewer::layout_for(options_.width, options_.height, show_panel_);
    // a drag under way: the pointer moves linearly from its press point
    if (script_dragging_) {
      const double s = std::clamp((t - script_drag_.at_s) / script_drag_.duration_s, 0.0, 1.0);
      drive_move(script_press_px_ + static_cast<float>(s) *
                                        Eigen::Vector2f(static_cast<float>(script_drag_.dx_px),
                                                        static_cast<float>(script_drag_.dy_px)),
                 layout);
      if (s >= 1.0) {
        drive_->release();
        script_dragging_ = false;
      }
    }
    if (script_key_until_s_ >= 0.0) {
      const double dt = std::min(t, script_key_until_s_) - script_key_last_s_;
      drive_->nudge(script_key_dir_, dt);
      script_key_last_s_ = std::min(t, script_key_until_s_);
      if (t >= script_key_until_s_) script_key_until_s_ = -1.0;
    }
    while (!script_.empty() && script_.front().at_s <= t) {
      const viewer::ScriptAction a = script_.front();
      script_.erase(script_.begin());
      std::cerr << "teleop_viewer: script t=" << t << " s:" << a.text << "\n";
      switch (a.kind) {
        case viewer::ScriptAction::Kind::kDrag: {
          Eigen::Vector2f at;
          if (hand_world(hand) &&
              camera_.project(hand.cast<float>(), static_cast<float>(layout.view_width),
                              static_cast<float>(layout.view_height), at) &&
              drive_press(at, layout)) {
            script_press_px_ = at;
            script_drag_ = a;
            script_dragging_ = true;
          } else {
            std::cerr
                << "teleop_viewer: script: the master's hand is not on screen; drag skipped\n";
          }
          break;
        }
        case viewer::ScriptAction::Kind::kKey:
          script_key_dir_ = a.key_direction;
          script_key_last_s_ = a.at_s;
          script_key_until_s_ = a.at_s + a.duration_s;
          break;
        case viewer::ScriptAction::Kind::kTune:
          // type the script's fields into the form, then press Apply with those fields
          if (a.fields & TUNE_MASTER_STIFFNESS) {
            tuning_form_.master_stiffness_n_per_m = a.master_stiffness_n_per_m;
          }
          if (a.fields & TUNE_MASTER_DAMPING) {
            tuning_form_.master_damping_ns_per_m = a.master_damping_ns_per_m;
          }
          if (a.fields & TUNE_FORCE_GAIN) tuning_form_.force_gain = a.force_gain;
          if (a.fields & TUNE_SLAVE_STIFFNESS) {
            tuning_form_.slave_stiffness_n_per_m = a.slave_stiffness_n_per_m;
          }
          if (a.fields & TUNE_FORWARD_DELAY) tuning_form_.forward_delay_ms = a.forward_delay_ms;
          if (a.fields & TUNE_BACKWARD_DELAY) tuning_form_.backward_delay_ms = a.backward_delay_ms;
          tuning_form_.ramp_s = a.ramp_s;
          send_tuning(a.fields);
          break;
        case viewer::ScriptAction::Kind::kSnapshot:
          save_path_ = a.path;  // written after the next frame is drawn
          save_requested_ = true;
          break;
        case viewer::ScriptAction::Kind::kQuit:
          return false;
      }
    }
    return true;
  }

 public:
  /// The drive summary: printed, and written to --drive-json.
  void finish_drive() const {
    if (!drive_) return;
    const std::string json = drive_->summary_json();
    std::printf("teleop_viewer: drive %s\n", json.c_str());
    std::fflush(stdout);
    if (!options_.drive_json.empty()) {
      teleop::write_text_file(options_.drive_json, json + "\n");  // throws naming the file
    }
  }

 private:
  /// Receive rates and frame-time percentiles, refreshed once a second.
  void update_rates(std::int64_t now) {
    if (rates_ns_ == 0) {
      rates_ns_ = now;
      last_counters_ = data_.counters();
      return;
    }
    const double dt = seconds_between(rates_ns_, now);
    if (dt < 1.0) return;
    const viewer::Counters c = data_.counters();
    panel_info_.slave_hz = static_cast<double>(c.slave_states - last_counters_.slave_states) / dt;
    {
      std::lock_guard<std::mutex> lock(server_mutex_);
      panel_info_.server = server_;
      panel_info_.servers = static_cast<int>(server_writers_.size());
    }
    panel_info_.master_hz =
        static_cast<double>(c.master_states - last_counters_.master_states) / dt;
    panel_info_.mesh_hz = static_cast<double>(c.frames - last_counters_.frames) / dt;
    panel_info_.stats_hz = static_cast<double>(c.server_stats - last_counters_.server_stats) / dt;
    panel_info_.fps = static_cast<double>(frames_ - last_frames_) / dt;
    last_frames_ = frames_;
    last_counters_ = c;
    rates_ns_ = now;
    frame_ms_.snapshot_into(frame_scratch_);
    if (!frame_scratch_.empty()) {
      const Summary s = summarize_in_place(frame_scratch_);
      panel_info_.frame_ms_p50 = s.p50;
      panel_info_.frame_ms_p99 = s.p99;
    }
  }

  std::string robot_status() const {
    if (!view_.have_scene()) return "robot: -";
    if (view_.scene.joint_count() == 0) return "no robot: a free tool (orange)";
    if (renderer_.skeleton().joints > 0) return "robot: skeleton from the scene's frames";
    return "robot: tip only (no link frames in the scene)";
  }

  void shutdown() {
    drive_.reset();
    // readers first: their callbacks write into data_
    r_experiment_.reset();
    r_events_.reset();
    r_stats_.reset();
    r_master_.reset();
    r_slave_.reset();
    r_frames_.reset();
    r_topology_.reset();
    r_scene_.reset();
    participant_.reset();
    if (window_) {
      glfwMakeContextCurrent(window_);
      target_.release();
      renderer_.release();
    }
    if (imgui_ready_) {
      ImGui_ImplOpenGL3_Shutdown();
      ImGui_ImplGlfw_Shutdown();
      ImGui::DestroyContext();
      imgui_ready_ = false;
    }
    if (window_) glfwDestroyWindow(window_);
    window_ = nullptr;
    if (glfw_ready_) glfwTerminate();
    glfw_ready_ = false;
  }

  Options options_;
  teleop::dds::ParticipantOptions dds_options_;
  bool headless_;
  std::int64_t t0_ns_;
  ViewerData data_;
  ViewerView view_;
  std::unique_ptr<teleop::dds::Participant> participant_;
  // which server the viewer watches (the participant writing slave_state), and every participant
  // that wrote the server's topics (reader threads)
  std::mutex server_mutex_;
  std::string server_;
  std::vector<eprosima::fastrtps::rtps::GuidPrefix_t> server_writers_;

  void note_server(const eprosima::fastdds::dds::SampleInfo& info, bool state) {
    const auto& prefix = info.sample_identity.writer_guid().guidPrefix;
    std::lock_guard<std::mutex> lock(server_mutex_);
    if (std::find(server_writers_.begin(), server_writers_.end(), prefix) ==
        server_writers_.end()) {
      server_writers_.push_back(prefix);
    }
    if (state) server_ = teleop::dds::guid_prefix_text(prefix);
  }

  std::unique_ptr<teleop::dds::Reader<SceneDescriptionPubSubType>> r_scene_;
  std::unique_ptr<teleop::dds::Reader<MeshTopologyPubSubType>> r_topology_;
  std::unique_ptr<teleop::dds::Reader<MeshFramePubSubType>> r_frames_;
  std::unique_ptr<teleop::dds::Reader<SlaveStatePubSubType>> r_slave_;
  std::unique_ptr<teleop::dds::Reader<MasterStatePubSubType>> r_master_;
  std::unique_ptr<teleop::dds::Reader<ServerStatsPubSubType>> r_stats_;
  std::unique_ptr<teleop::dds::Reader<ExperimentDescriptionPubSubType>> r_experiment_;
  std::unique_ptr<teleop::dds::Reader<EventPubSubType>> r_events_;

  GLFWwindow* window_ = nullptr;
  bool glfw_ready_ = false;
  bool imgui_ready_ = false;
  std::string renderer_name_, gl_version_;
  viewer::SceneRenderer renderer_;
  viewer::OffscreenTarget target_;
  int msaa_ = 4;
  bool software_ = false;  ///< drawn by a software rasteriser (llvmpipe, softpipe, swrast)
  viewer::OrbitCamera camera_;
  viewer::RenderOptions render_options_;
  viewer::PanelInfo panel_info_;
  bool show_panel_ = true;
  bool paused_ = false;
  bool save_requested_ = false;
  std::string save_path_;  ///< where the next save goes ("" = a timestamped name)

  SampleWindow frame_ms_;
  std::vector<double> frame_scratch_;
  std::uint64_t frames_ = 0, last_frames_ = 0;
  std::int64_t rates_ns_ = 0;
  viewer::Counters last_counters_;

  // drive
  std::unique_ptr<viewer::DriveSession> drive_;
  viewer::TuningForm tuning_form_;
  std::vector<viewer::ScriptAction> script_;
  std::int64_t script_t0_ns_ = 0;
  viewer::ScriptAction script_drag_;  // the drag under way (when script_dragging_)
  bool script_dragging_ = false;
  bool mouse_dragging_ = false;  // a drag started with the mouse
  Eigen::Vector2f script_press_px_ = Eigen::Vector2f::Zero();
  Eigen::Vector3d script_key_dir_ = Eigen::Vector3d::Zero();
  double script_key_last_s_ = 0.0;
  double script_key_until_s_ = -1.0;
};

}  // namespace

namespace {

/// Declares every flag of teleop_viewer.
void add_flags(CLI::App& app, Options& o, teleop::dds::NetworkFlags& net_flags) {
  app.add_option("--domain", o.domain, "DDS domain id, 0-232 (default: $TELEOP_DOMAIN or 0)")
      ->check(teleop::config::integer_in(0.0, 232.0));
  app.add_option("--profile", o.profile, "Fast DDS profile (default: loopback)");
  teleop::dds::add_network_flags(app, net_flags);
  app.add_option("--snapshot", o.snapshot,
                 "headless: render offscreen, write this PNG and exit (needs an X display, e.g. "
                 "xvfb-run)");
  app.add_option("--after", o.after_s,
                 "snapshot after this many seconds of complete data [s], 0-3600")
      ->capture_default_str();
  app.add_option("--timeout", o.timeout_s,
                 "snapshot: give up (exit 3) when the data is not complete by then [s], 0.1-3600")
      ->capture_default_str();
  app.add_option("--width", o.width, "window or snapshot width [px], 320-7680")
      ->capture_default_str();
  app.add_option("--height", o.height, "window or snapshot height [px], 240-4320")
      ->capture_default_str();
  app.add_option("--fps", o.fps,
                 "frame rate cap [Hz], 0-1000; 0 = the display rate (vsync), or 15 on a "
                 "software renderer (llvmpipe)")
      ->capture_default_str();
  app.add_option("--history", o.history_s, "plot window [s], 1-600")->capture_default_str();
  app.add_option("--duration", o.duration_s, "close after this long [s], 0-1e7; 0 = until closed")
      ->check(teleop::config::number_in(0.0, 1e7));
  app.add_option("--msaa", o.msaa,
                 "samples per pixel for anti-aliasing, 0-16 (default: 4; 0 in a window drawn by "
                 "a software renderer such as llvmpipe)")
      ->check(teleop::config::integer_in(0.0, 16.0));
  app.add_option("--force-scale", o.force_scale_m_per_n,
                 "contact force arrow length per newton [m/N], 0.0001-10")
      ->capture_default_str();
  app.add_option("--displacement-scale", o.displacement_scale_m,
                 "deformation drawn fully red [m], 0.00001-1")
      ->capture_default_str();
  app.add_option("--nice", o.nice,
                 "scheduling niceness of the viewer, 0-19: it yields the CPU to the server and "
                 "master on the same machine")
      ->check(teleop::config::integer_in(0.0, 19.0))
      ->capture_default_str();
  app.add_flag("--full-rate", o.full_rate,
               "read the 1 kHz state topics instead of the 60 Hz *_view copies; loads the loops");
  app.add_flag("--hide-panel", o.hide_panel, "start without the plot panel (key H)");
  app.add_flag("--wireframe", o.wireframe, "start with wireframe meshes (key W)");
  app.add_flag("--drive", o.drive,
               "drive the session by hand: be the master's device (teleop_master --device "
               "external) and its tuning tool (teleop_master --accept-tuning)");
  app.add_option("--input-script", o.input_script,
                 "with --drive: play mouse, key and tuning input from this file (docs/tools.md)");
  app.add_option("--drive-json", o.drive_json, "with --drive: write the drive summary here");
  app.add_option("--drive-scale", o.drive_scale,
                 "slave metres per device metre (the master's position scale), 0.001-1000")
      ->capture_default_str();
  app.add_option("--drive-peak-force", o.drive_peak_force_n,
                 "the device's declared peak force [N] (the force bar's full scale), 0.1-1000")
      ->capture_default_str();
  app.add_flag("--plain", o.plain_colours,
               "start with meshes in their plain colour instead of coloured by deformation "
               "(key C)");
}

/// An observer must not take the CPU from the control loops on the same machine. Lowers the
/// priority (--nice) before any thread starts (the renderer's, DDS's), so they all inherit it;
/// and keeps Mesa's software rasteriser (llvmpipe) on the render thread instead of one thread per
/// core, whose helper threads raise the master's loop jitter (docs/viewer.md). A value the user
/// set wins; other drivers ignore the variable.
void yield_to_control_loops(const Options& o) {
  if (o.nice > 0 && setpriority(PRIO_PROCESS, 0, o.nice) != 0) {
    std::cerr << "teleop_viewer: warning: cannot lower the priority (--nice " << o.nice << ")\n";
  }
  setenv("LP_NUM_THREADS", "0", 0);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"teleop_viewer: 3-D observer of a teleoperation session (scene, plots, events)"};
  Options o;
  teleop::dds::NetworkFlags net_flags;
  add_flags(app, o, net_flags);
  if (const int status = teleop::config::parse_command_line(app, "teleop_viewer", argc, argv);
      status >= 0) {
    return status == 2 ? kExitUsage : status;
  }
  try {
    validate(o);
    if (!o.drive_json.empty()) prepare_output_file("--drive-json", o.drive_json);
    // driving publishes the device and tuning topics: the secure profiles' operator role
    if (o.drive) net_flags.default_identity = "operator";
    yield_to_control_loops(o);
    const auto dds_options =
        teleop::dds::resolve_participant_options(o.profile, o.domain, "teleop_viewer", net_flags);
    teleop::dds::profile_file(dds_options.profile);  // fail early with the list of profiles
    install_stop_signal_handlers();
    std::vector<teleop::viewer::ScriptAction> script;
    if (!o.input_script.empty()) script = teleop::viewer::parse_input_script(o.input_script);
    ViewerApp viewer(o, dds_options);
    if (const int status = viewer.init_graphics(); status != 0) return status;
    viewer.init_dds();
    viewer.set_script(std::move(script));
    const int status = viewer.run();
    viewer.print_summary();
    viewer.finish_drive();
    return status;
  } catch (const config::ConfigError& e) {
    std::cerr << "teleop_viewer: " << e.what() << "\n";
    return kExitUsage;
  } catch (const std::exception& e) {
    std::cerr << "teleop_viewer: error: " << e.what() << "\n";
    return kExitRuntime;
  }
}
