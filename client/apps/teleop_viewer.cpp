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
// Threads: one DDS reader thread per topic (viewer::ViewerLink) copies each sample into the
// ViewerSession's data store (short mutex, no allocation after warm-up); the render loop here
// copies what changed once per frame and draws at the display rate (vsync) or --fps
// (viewer::FramePacer). Everything but the window, OpenGL and Dear ImGui lives in the viewer
// library (client/viewer/), unit-tested without a display.
//
// Drive (--drive, docs/tools.md "Drive it by hand"): the viewer is also the master's haptic
// device (teleop/device_state at 1 kHz from a 1 kHz thread; teleop_master --device external)
// and its tuning tool (teleop/tuning; teleop_master --accept-tuning). Drag the ring at the
// master's hand with the left button, or hold the arrows and PgUp/PgDn; the force the master
// renders is drawn as an arrow from the ring and as a bar. --input-script FILE plays the same
// input from a file (client/viewer/input_script.hpp) through the same viewer::DriveInput.
//
// Exit status: 0 done, 1 runtime failure (no display, OpenGL, DDS, file), 2 bad command line,
// 3 snapshot: the data never became complete within --timeout.
#include <sys/resource.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <memory>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "client/viewer/gl/gl_api.hpp"
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include "client/viewer/camera.hpp"
#include "client/viewer/drive_input.hpp"
#include "client/viewer/frame_timing.hpp"
#include "client/viewer/gl/offscreen.hpp"
#include "client/viewer/gl/renderer.hpp"
#include "client/viewer/input_script.hpp"
#include "client/viewer/png.hpp"
#include "client/viewer/script_player.hpp"
#include "client/viewer/ui/drive_panel.hpp"
#include "client/viewer/ui/panel.hpp"
#include "client/viewer/viewer_data.hpp"
#include "client/viewer/viewer_link.hpp"
#include "client/viewer/viewer_options.hpp"
#include "client/viewer/viewer_session.hpp"
#include "common/config/config.hpp"
#include "common/config/flags.hpp"
#include "common/dds/network_flags.hpp"
#include "common/util/clock.hpp"
#include "common/util/files.hpp"
#include "common/util/signals.hpp"

namespace {

using namespace teleop;
using viewer::ViewerOptions;

constexpr int kExitRuntime = 1;
constexpr int kExitUsage = 2;
constexpr int kExitNoData = 3;

class ViewerApp {
 public:
  ViewerApp(const ViewerOptions& options, const teleop::dds::ParticipantOptions& dds_options)
      : options_(options),
        dds_options_(dds_options),
        headless_(!options.snapshot.empty()),
        session_(options.history_s, now_ns()) {
    render_options_.wireframe = options.wireframe;
    render_options_.displacement_colors = !options.plain_colours;
    render_options_.displacement_scale_m = static_cast<float>(options.displacement_scale_m);
    render_options_.force_scale_m_per_n = static_cast<float>(options.force_scale_m_per_n);
    show_panel_ = !options.hide_panel;
    panel_info_.domain = dds_options.domain;
    panel_info_.profile =
        dds_options.profile + (dds_options.insecure ? " INSECURE (no DDS Security)" : "");
    panel_info_.history_s = options.history_s;
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
    return init_ui();
  }

  /// The participant, its readers and, with --drive, the drive and the input script.
  void init_dds(std::vector<viewer::ScriptAction> script) {
    link_ = std::make_unique<viewer::ViewerLink>(dds_options_, options_, session_);
    if (link_->drive() == nullptr) return;
    drive_input_ = std::make_unique<viewer::DriveInput>(*link_->drive());
    if (!script.empty()) {
      script_ = std::make_unique<viewer::ScriptPlayer>(std::move(script), std::cerr);
    }
  }

  /// The render loop. Returns the exit status.
  int run() {
    viewer::FramePacer pacer(options_.fps, headless_, software_, now_ns());
    viewer::SnapshotGate gate(options_.after_s, options_.timeout_s);
    std::int64_t first_frame_ns = 0;
    while (true) {
      glfwPollEvents();
      if (stop_requested() || glfwWindowShouldClose(window_)) break;
      const std::int64_t frame_start = now_ns();
      if (first_frame_ns == 0) first_frame_ns = frame_start;
      const double elapsed_s = seconds_between(session_.t0_ns(), frame_start);
      if (options_.duration_s > 0.0 && elapsed_s >= options_.duration_s) break;
      if (!update(frame_start)) break;

      // headless: wait until the data is complete, then --after seconds more
      bool snapshot_now = false;
      if (headless_) {
        const viewer::SnapshotFrame s = gate.frame(view_.complete(), frame_start, elapsed_s);
        if (s.became_complete) {
          std::cerr << "teleop_viewer: data complete after " << elapsed_s << " s (scene '"
                    << view_.scene.name() << "'), snapshot in " << options_.after_s << " s\n";
        }
        if (s.give_up) {
          std::cerr << "teleop_viewer: no complete data on domain " << dds_options_.domain
                    << " within --timeout " << options_.timeout_s
                    << " s (missing: " << view_.missing()
                    << "). Is a teleop_server running on this domain and profile?\n";
          return kExitNoData;
        }
        snapshot_now = s.shoot;
      }

      // headless: the frames before the snapshot only lay the UI out; only the last one is drawn
      const int status = draw_frame(!headless_ || snapshot_now, snapshot_now);
      if (status >= 0) return status;
      const std::int64_t frame_end = now_ns();
      session_.record_frame(frame_start, frame_end);
      pace(pacer, first_frame_ns, frame_end);
    }
    return 0;
  }

  /// Prints the frame statistics of a window (headless frames only lay the UI out).
  void print_summary() const {
    if (headless_) return;
    const viewer::RenderSetup setup{target_.width(), target_.height(), msaa_, renderer_name_};
    const std::string line = session_.frame_summary(setup, now_ns(), viewer::process_cpu_s());
    if (line.empty()) return;
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  }

  /// The drive summary: printed, and written to --drive-json.
  void finish_drive() const {
    const viewer::DriveSession* drive = link_ ? link_->drive() : nullptr;
    if (drive == nullptr) return;
    const std::string json = drive->summary_json();
    std::printf("teleop_viewer: drive %s\n", json.c_str());
    std::fflush(stdout);
    if (!options_.drive_json.empty()) {
      teleop::write_text_file(options_.drive_json, json + "\n");  // throws naming the file
    }
  }

 private:
  /// Dear ImGui on the window, and the renderer. Returns an exit status, or 0 on success.
  int init_ui() {
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

  /// The frame's data: the view (unless paused), the renderer's scene and meshes, the panel's
  /// rates, the input script. Returns false when the script quits.
  bool update(std::int64_t frame_start) {
    if (!paused_) session_.data().update(view_);
    renderer_.sync_scene(view_);
    if (view_.have_scene()) renderer_.upload_deformables(view_, render_options_);
    if (session_.update_rates(frame_start)) show_status(session_.status());
    return !script_ || play_script(frame_start);
  }

  void show_status(const viewer::ReceiveStatus& s) {
    panel_info_.server = s.server;
    panel_info_.servers = s.servers;
    panel_info_.slave_hz = s.slave_hz;
    panel_info_.master_hz = s.master_hz;
    panel_info_.mesh_hz = s.mesh_hz;
    panel_info_.stats_hz = s.stats_hz;
    panel_info_.fps = s.fps;
    panel_info_.frame_ms_p50 = s.frame_ms_p50;
    panel_info_.frame_ms_p99 = s.frame_ms_p99;
  }

  /// Plays the input script's due actions; the pointer moves in the layout of the requested
  /// window size. Returns false when the script quits.
  bool play_script(std::int64_t now) {
    const viewer::Layout layout = viewer::layout_for(options_.width, options_.height, show_panel_);
    viewer::ScriptStep step = script_->step(now, view_, camera_, layout, *drive_input_);
    if (step.save) {
      save_path_ = std::move(step.save_path);  // written after the next frame is drawn
      save_requested_ = true;
    }
    return !step.quit;
  }

  /// Sleeps until the next frame is due; after the first frames under vsync, paces at the
  /// display's rate when the display does not throttle.
  void pace(viewer::FramePacer& pacer, std::int64_t first_frame_ns, std::int64_t frame_end) {
    if (pacer.vsync_check_due(session_.frames())) {
      const double measured_hz = static_cast<double>(viewer::FramePacer::kVsyncCheckFrames - 1) /
                                 seconds_between(first_frame_ns, frame_end);
      const double display_hz = display_refresh_hz();
      if (pacer.pace_if_unthrottled(measured_hz, display_hz)) {
        std::cerr << "teleop_viewer: the display does not throttle (" << measured_hz
                  << " fps; no vsync, e.g. Xvfb or a remote X server): pacing at " << display_hz
                  << " fps (--fps to choose)\n";
      }
    }
    const std::int64_t sleep = pacer.sleep_ns(frame_end, now_ns());
    if (sleep > 0) std::this_thread::sleep_for(std::chrono::nanoseconds(sleep));
  }

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
    draw_ui(layout, fb_w, fb_h);
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

  /// The panel, the overlay and the drive window, for a framebuffer of fb_w x fb_h.
  void draw_ui(const viewer::Layout& layout, int fb_w, int fb_h) {
    panel_info_.now_s = seconds_between(session_.t0_ns(), now_ns());
    panel_info_.paused = paused_;
    panel_info_.wireframe = render_options_.wireframe;
    panel_info_.displacement_colors = render_options_.displacement_colors;
    panel_info_.robot_status = viewer::robot_status(view_, renderer_.skeleton().joints);
    panel_info_.max_displacement_m = renderer_.max_displacement_m();
    panel_info_.headless = headless_;
    panel_info_.width = fb_w;
    panel_info_.height = fb_h;
    panel_info_.msaa = msaa_;
    viewer::draw_panel(view_, panel_info_, layout);
    viewer::draw_overlay(view_, panel_info_);
    if (drive_input_) draw_drive(layout);
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

  /// Keys, then the pointer: the drive's first (--drive), else the camera's.
  void handle_input(const viewer::Layout& layout) {
    const ImGuiIO& io = ImGui::GetIO();
    if (!io.WantCaptureKeyboard) handle_keys();
    if (drive_input_ && drive_pointer(layout)) return;
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

  /// The view's keys: R camera, W wireframe, C colours, F force, H panel, P/space pause,
  /// S save, Q/Esc quit.
  void handle_keys() {
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

  // ---- drive (--drive) ----

  /// Held arrows and PgUp/PgDn, and the pointer, to the drive. Returns true when the drive
  /// took the pointer (the camera stays).
  bool drive_pointer(const viewer::Layout& layout) {
    const ImGuiIO& io = ImGui::GetIO();
    if (!io.WantCaptureKeyboard) {
      viewer::DriveKeys k;
      k.right = ImGui::IsKeyDown(ImGuiKey_RightArrow);
      k.left = ImGui::IsKeyDown(ImGuiKey_LeftArrow);
      k.up = ImGui::IsKeyDown(ImGuiKey_UpArrow);
      k.down = ImGui::IsKeyDown(ImGuiKey_DownArrow);
      k.page_up = ImGui::IsKeyDown(ImGuiKey_PageUp);
      k.page_down = ImGui::IsKeyDown(ImGuiKey_PageDown);
      drive_input_->keys(viewer::key_direction(k), io.DeltaTime);
    }
    viewer::PointerInput p;
    p.position_px = Eigen::Vector2f(io.MousePos.x, io.MousePos.y);
    p.left_down = ImGui::IsMouseDown(ImGuiMouseButton_Left);
    p.left_clicked = ImGui::IsMouseClicked(ImGuiMouseButton_Left);
    p.shift = io.KeyShift;
    p.ui_wants_mouse = io.WantCaptureMouse;
    const bool script_drags = script_ && script_->dragging();
    return drive_input_->pointer(p, script_drags, view_, camera_, layout);
  }

  void draw_drive(const viewer::Layout& layout) {
    const viewer::DriveSession& drive = *link_->drive();
    const viewer::DriveView v = drive.view();
    Eigen::Vector3d hand;
    if (viewer::hand_world(view_, hand)) {
      viewer::draw_drive_overlay(camera_, static_cast<float>(layout.view_width),
                                 static_cast<float>(layout.view_height), hand, v,
                                 options_.force_scale_m_per_n, drive.dragging());
    }
    const std::uint32_t fields = viewer::draw_drive_window(
        v, drive.peak_force_n(), drive_input_->form(), static_cast<float>(layout.view_height));
    if (fields != 0) drive_input_->send_tuning(fields);
  }

  void shutdown() {
    // the DDS side first: its reader callbacks write into session_
    script_.reset();
    drive_input_.reset();
    link_.reset();
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

  ViewerOptions options_;
  teleop::dds::ParticipantOptions dds_options_;
  bool headless_;
  viewer::ViewerSession session_;
  viewer::ViewerView view_;
  std::unique_ptr<viewer::ViewerLink> link_;
  std::unique_ptr<viewer::DriveInput> drive_input_;  ///< --drive
  std::unique_ptr<viewer::ScriptPlayer> script_;     ///< --drive --input-script

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
};

/// An observer must not take the CPU from the control loops on the same machine. Lowers the
/// priority (--nice) before any thread starts (the renderer's, DDS's), so they all inherit it;
/// and keeps Mesa's software rasteriser (llvmpipe) on the render thread instead of one thread per
/// core, whose helper threads raise the master's loop jitter (docs/viewer.md). A value the user
/// set wins; other drivers ignore the variable.
void yield_to_control_loops(const ViewerOptions& o) {
  if (o.nice > 0 && setpriority(PRIO_PROCESS, 0, o.nice) != 0) {
    std::cerr << "teleop_viewer: warning: cannot lower the priority (--nice " << o.nice << ")\n";
  }
  setenv("LP_NUM_THREADS", "0", 0);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"teleop_viewer: 3-D observer of a teleoperation session (scene, plots, events)"};
  ViewerOptions o;
  teleop::dds::NetworkFlags net_flags;
  viewer::add_viewer_flags(app, o, net_flags);
  if (const int status = teleop::config::parse_command_line(app, "teleop_viewer", argc, argv);
      status >= 0) {
    return status == 2 ? kExitUsage : status;
  }
  try {
    viewer::validate_options(o);
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
    viewer.init_dds(std::move(script));
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
