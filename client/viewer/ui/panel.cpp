#include "client/viewer/ui/panel.hpp"

#include "common/dds/event_kinds.hpp"
#include "common/dds/experiment_text.hpp"

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace teleop::viewer {
namespace {

const ImU32 kPlotBackground = IM_COL32(28, 30, 36, 255);
const ImU32 kPlotBorder = IM_COL32(70, 74, 84, 255);
const ImU32 kPlotGrid = IM_COL32(55, 58, 66, 255);
const ImU32 kAxisText = IM_COL32(150, 154, 164, 255);

const ImU32 kOrange = IM_COL32(250, 130, 40, 255);
const ImU32 kBlue = IM_COL32(90, 170, 250, 255);
const ImU32 kGreen = IM_COL32(110, 210, 120, 255);
const ImU32 kRed = IM_COL32(240, 90, 90, 255);
const ImU32 kViolet = IM_COL32(190, 140, 250, 255);

struct PlotLine {
  const TimeSeries* series;
  ImU32 color;
  const char* label;
};

/// The title row: the plot's name, then the newest value of each line in its colour.
void plot_title(const char* title, const char* unit, const PlotLine* lines, int line_count) {
  ImGui::TextUnformatted(title);
  for (int i = 0; i < line_count; ++i) {
    const TimeSeries& s = *lines[i].series;
    char text[96];
    if (s.empty()) {
      std::snprintf(text, sizeof(text), "%s --", lines[i].label);
    } else {
      std::snprintf(text, sizeof(text), "%s %.3g %s", lines[i].label,
                    static_cast<double>(s.newest().last), unit);
    }
    ImGui::SameLine();
    ImGui::TextColored(ImGui::ColorConvertU32ToFloat4(lines[i].color), "%s", text);
  }
}

/// A plot's rectangle on the screen and the time and value ranges it shows.
struct PlotFrame {
  ImVec2 p0, p1;
  float width = 0.0f, height = 0.0f;
  double t_begin = 0.0, history_s = 1.0;
  double lo = 0.0, hi = 1.0;
  bool have_data = false;  ///< some line has a bucket in the time range
  float y(double v) const {
    return p1.y - static_cast<float>((v - lo) / (hi - lo)) * (height - 2.0f) - 1.0f;
  }
  float x(double t) const { return p0.x + static_cast<float>((t - t_begin) / history_s) * width; }
};

/// The vertical range over the visible buckets, padded (from_zero: it includes zero).
void plot_range(const PlotLine* lines, int line_count, bool from_zero, PlotFrame& f) {
  double lo = 1e300, hi = -1e300;
  for (int i = 0; i < line_count; ++i) {
    const TimeSeries& s = *lines[i].series;
    for (std::size_t k = 0; k < s.size(); ++k) {
      if (s[k].t_s < f.t_begin) continue;
      lo = std::min(lo, static_cast<double>(s[k].min));
      hi = std::max(hi, static_cast<double>(s[k].max));
    }
  }
  f.have_data = lo <= hi;
  if (!f.have_data) {
    lo = 0.0;
    hi = 1.0;
  }
  if (from_zero) {
    lo = std::min(lo, 0.0);
    hi = std::max(hi, 0.0);
  }
  if (hi - lo < 1e-9) {  // flat: a unit range around the value (from zero: above it)
    const double pad = std::max(std::abs(hi) * 0.1, 1.0);
    if (!(from_zero && lo == 0.0)) lo -= pad;
    hi += pad;
  } else {
    const double pad = 0.08 * (hi - lo);
    if (!(from_zero && lo == 0.0)) lo -= pad;
    hi += pad;
  }
  f.lo = lo;
  f.hi = hi;
}

/// Horizontal grid lines with their values: three, or two on a short plot.
void plot_grid(ImDrawList* dl, const PlotFrame& f) {
  const int grid_lines = f.height >= 4.5f * ImGui::GetFontSize() ? 3 : 2;
  for (int g = 0; g < grid_lines; ++g) {
    const double v = f.lo + (f.hi - f.lo) * (0.25 + 0.5 * g / (grid_lines - 1));
    const float y = f.y(v);
    dl->AddLine(ImVec2(f.p0.x, y), ImVec2(f.p1.x, y), kPlotGrid);
    char text[32];
    std::snprintf(text, sizeof(text), "%.3g", v);
    dl->AddText(ImVec2(f.p0.x + 3.0f, y - 0.5f * ImGui::GetFontSize()), kAxisText, text);
  }
}

/// One line: one point per pixel column (its last value) and, where the column's values span
/// more than a pixel, a vertical stroke from its minimum to its maximum: a one-sample spike shows.
void plot_series(ImDrawList* dl, const PlotFrame& f, const PlotLine& line) {
  static std::vector<ImVec2> points;  // render thread only; keeps its capacity
  const TimeSeries& s = *line.series;
  points.clear();
  const ImU32 spike = (line.color & 0x00ffffffu) | 0x70000000u;
  int column = -1;
  float col_x = 0.0f, col_min = 0.0f, col_max = 0.0f, col_last = 0.0f;
  const auto flush = [&] {
    if (column < 0) return;
    const float y_min = f.y(col_min), y_max = f.y(col_max);
    if (y_min - y_max > 1.0f) dl->AddLine(ImVec2(col_x, y_min), ImVec2(col_x, y_max), spike);
    points.push_back(ImVec2(col_x, f.y(col_last)));
  };
  for (std::size_t k = 0; k < s.size(); ++k) {
    const auto& b = s[k];
    if (b.t_s + s.bucket_s() < f.t_begin) continue;
    const float x = f.x(b.t_s);
    const int c = static_cast<int>(std::floor(x));
    if (c != column) {
      flush();
      column = c;
      col_x = x;
      col_min = b.min;
      col_max = b.max;
    } else {
      col_min = std::min(col_min, b.min);
      col_max = std::max(col_max, b.max);
    }
    col_last = b.last;
  }
  flush();
  if (points.size() >= 2) {
    dl->AddPolyline(points.data(), static_cast<int>(points.size()), line.color, 0, 1.5f);
  }
}

/// Title row with the newest value of each line, then a plot of the last history_s seconds.
void plot(const char* title, const char* unit, const PlotLine* lines, int line_count,
          const PanelInfo& info, float height, bool from_zero) {
  plot_title(title, unit, lines, line_count);
  PlotFrame f;
  f.p0 = ImGui::GetCursorScreenPos();
  f.width = ImGui::GetContentRegionAvail().x;
  f.height = height;
  f.p1 = ImVec2(f.p0.x + f.width, f.p0.y + height);
  f.t_begin = info.now_s - info.history_s;
  f.history_s = info.history_s;
  ImGui::Dummy(ImVec2(f.width, height));
  ImDrawList* dl = ImGui::GetWindowDrawList();
  dl->AddRectFilled(f.p0, f.p1, kPlotBackground);
  plot_range(lines, line_count, from_zero, f);
  plot_grid(dl, f);
  dl->PushClipRect(f.p0, f.p1, true);
  for (int i = 0; i < line_count; ++i) plot_series(dl, f, lines[i]);
  dl->PopClipRect();
  dl->AddRect(f.p0, f.p1, kPlotBorder);
  if (!f.have_data) {
    const char* empty = "no data";
    const ImVec2 sz = ImGui::CalcTextSize(empty);
    dl->AddText(ImVec2(0.5f * (f.p0.x + f.p1.x - sz.x), 0.5f * (f.p0.y + f.p1.y - sz.y)), kAxisText,
                empty);
  }
  ImGui::Spacing();
}

/// The panel's first lines: the domain, the server, the scene, the topics' rates, the render.
void panel_header(const ViewerView& view, const PanelInfo& info) {
  ImGui::Text("teleop_viewer   domain %d   %s", info.domain, info.profile.c_str());
  if (!info.server.empty()) ImGui::Text("server %s", info.server.c_str());
  if (info.servers > 1) {
    ImGui::TextColored(ImVec4(1.0f, 0.4f, 0.3f, 1.0f), "%d participants write the server's topics",
                       info.servers);
  }
  if (view.have_scene()) {
    ImGui::Text("scene '%s'  %u joints  %lu objects", view.scene.name().c_str(),
                view.scene.joint_count(), static_cast<unsigned long>(view.scene.objects().size()));
  } else {
    ImGui::TextColored(ImVec4(1.0f, 0.8f, 0.3f, 1.0f), "waiting for teleop/scene ...");
  }
  ImGui::Text("slave_state %.0f Hz   mesh_frame %.0f Hz", info.slave_hz, info.mesh_hz);
  ImGui::Text("master_state %.0f Hz   server_stats %.1f Hz", info.master_hz, info.stats_hz);
  if (info.headless) {
    ImGui::Text("snapshot %dx%d, %dx MSAA", info.width, info.height, info.msaa);
  } else {
    ImGui::Text("render %.0f fps  frame %.1f ms (p99 %.1f)", info.fps, info.frame_ms_p50,
                info.frame_ms_p99);
  }
  ImGui::TextDisabled("%s", info.robot_status.c_str());
  ImGui::TextDisabled("plots: the last %.0f s", info.history_s);
  if (info.paused) {
    ImGui::SameLine();
    ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.35f, 1.0f), "  PAUSED");
  }
}

/// The plots, their height shared out of the window's.
void panel_plots(const ViewerView& view, const PanelInfo& info, const Layout& layout) {
  const float h =
      std::clamp((static_cast<float>(layout.view_height) - 440.0f) / 6.0f, 32.0f, 110.0f);
  {
    const PlotLine l[] = {{&view.series[kForceN], kOrange, "|F|"}};
    plot("contact force", "N", l, 1, info, h, true);
  }
  {
    const PlotLine l[] = {{&view.series[kPenetrationMm], kBlue, "penetration"},
                          {&view.series[kDeformationMm], kGreen, "deformation"}};
    plot("tip", "mm", l, 2, info, h, true);
  }
  {
    const PlotLine l[] = {{&view.series[kStepP50Us], kGreen, "p50"},
                          {&view.series[kStepP99Us], kRed, "p99"}};
    plot("step time", "us", l, 2, info, h, true);
  }
  {
    const PlotLine l[] = {{&view.series[kLoopRateHz], kBlue, "rate"}};
    plot("physics loop", "Hz", l, 1, info, h, false);
  }
  {
    const PlotLine l[] = {{&view.series[kRoundTripMs], kViolet, "rtt"}};
    plot("master round trip", "ms", l, 1, info, h, true);
  }
  {
    const PlotLine l[] = {{&view.series[kEnergyJ], kOrange, "E"}};
    plot("master port energy", "J", l, 1, info, h, true);
  }
}

/// The events, newest last, over the key help (which wraps to the panel's width).
void panel_events(const ViewerView& view, const PanelInfo& info) {
  ImGui::Text("events (%llu)", static_cast<unsigned long long>(view.counters.events));
  // the key help wraps to the panel's width, so every key shows however narrow the panel is
  char help[160];
  std::snprintf(help, sizeof help,
                "drag: orbit  right-drag: pan  wheel: zoom  R view  W wire%s  C colour%s  "
                "F force  H panel  P pause  S save  Q quit",
                info.wireframe ? "*" : "", info.displacement_colors ? "*" : "");
  const float wrap_w = ImGui::GetContentRegionAvail().x;
  const float help_h =
      ImGui::CalcTextSize(help, nullptr, false, wrap_w).y + ImGui::GetStyle().ItemSpacing.y + 6.0f;
  ImGui::BeginChild("events", ImVec2(0.0f, -help_h), false);
  for (int i = 0; i < view.event_count; ++i) {
    const EventEntry& e = view.events[static_cast<std::size_t>(i)];
    const ImVec4 color = e.severity >= 2   ? ImVec4(1.0f, 0.4f, 0.4f, 1.0f)
                         : e.severity == 1 ? ImVec4(1.0f, 0.85f, 0.35f, 1.0f)
                                           : ImVec4(0.8f, 0.82f, 0.86f, 1.0f);
    ImGui::PushStyleColor(ImGuiCol_Text, color);
    ImGui::TextWrapped("%6.1f s %s %s: %s", e.t_s, e.source, dds::event_kind_name(e.kind),
                       e.message);
    ImGui::PopStyleColor();
  }
  ImGui::EndChild();
  ImGui::Separator();
  ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyle().Colors[ImGuiCol_TextDisabled]);
  ImGui::TextWrapped("%s", help);
  ImGui::PopStyleColor();
}

}  // namespace

void draw_panel(const ViewerView& view, const PanelInfo& info, const Layout& layout) {
  if (layout.panel_width <= 0) return;
  ImGui::SetNextWindowPos(ImVec2(static_cast<float>(layout.view_width), 0.0f), ImGuiCond_Always);
  ImGui::SetNextWindowSize(
      ImVec2(static_cast<float>(layout.panel_width), static_cast<float>(layout.view_height)),
      ImGuiCond_Always);
  const ImGuiWindowFlags flags = ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize |
                                 ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoTitleBar |
                                 ImGuiWindowFlags_NoSavedSettings;
  ImGui::Begin("teleop_viewer##panel", nullptr, flags);
  panel_header(view, info);
  ImGui::Separator();
  panel_plots(view, info, layout);
  ImGui::Separator();
  panel_events(view, info);
  ImGui::End();
}

void draw_overlay(const ViewerView& view, const PanelInfo& info) {
  ImGui::SetNextWindowPos(ImVec2(10.0f, 10.0f), ImGuiCond_Always);
  ImGui::SetNextWindowBgAlpha(0.45f);
  const ImGuiWindowFlags flags = ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoInputs |
                                 ImGuiWindowFlags_AlwaysAutoResize |
                                 ImGuiWindowFlags_NoSavedSettings |
                                 ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoNav;
  ImGui::Begin("##overlay", nullptr, flags);
  if (!view.complete()) {
    ImGui::TextColored(ImVec4(1.0f, 0.8f, 0.3f, 1.0f), "waiting for %s on domain %d",
                       view.missing().c_str(), info.domain);
  }
  if (view.have_slave) {
    const auto& s = view.slave;
    const auto& x = s.tip_position_m();
    const auto& f = s.contact_force_n();
    const double fn = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    ImGui::Text("t = %.2f s   tip (%.3f, %.3f, %.3f) m", s.sim_time_s(), x[0], x[1], x[2]);
    ImGui::Text("|F| %.2f N   penetration %.1f mm   deformation %.1f mm", fn,
                s.penetration_m() * 1e3, s.deformation_m() * 1e3);
    if (s.in_contact()) {
      ImGui::SameLine();
      ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.3f, 1.0f), "  CONTACT");
    }
    if (s.holding()) {
      ImGui::SameLine();
      ImGui::TextColored(ImVec4(1.0f, 0.85f, 0.35f, 1.0f), "  HOLDING");
    }
  }
  if (view.have_master) {
    ImGui::Text("master: rtt %.2f ms  energy %.3g J  link %s", view.master.rtt_ms(),
                view.master.passivity_energy_j(), view.master.link_ok() ? "ok" : "LOST");
  }
  if (view.have_experiment) {
    // what the session is (teleop/experiment): the rtt above is the network's alone
    ImGui::PushTextWrapPos(0.0f);
    if (view.experiment.driver_live()) {
      ImGui::TextUnformatted(("experiment: " + dds::experiment_text(view.experiment)).c_str());
    } else {
      ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.35f, 1.0f), "experiment: %s",
                         dds::experiment_text(view.experiment).c_str());
    }
    ImGui::PopTextWrapPos();
  } else {
    ImGui::TextDisabled("experiment: none described yet (no master on teleop/experiment)");
  }
  if (info.displacement_colors) {
    ImGui::Text("colours: deformation since the contact began, max %.1f mm",
                info.max_displacement_m * 1e3);
  }
  if (info.paused) ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.35f, 1.0f), "PAUSED (P to resume)");
  if (!info.note.empty()) ImGui::TextDisabled("%s", info.note.c_str());
  ImGui::End();
}

}  // namespace teleop::viewer
