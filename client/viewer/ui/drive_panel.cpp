#include "client/viewer/ui/drive_panel.hpp"

#include <imgui.h>

#include <algorithm>
#include <cmath>

namespace teleop::viewer {

void draw_drive_overlay(const OrbitCamera& camera, float view_w, float view_h,
                        const Eigen::Vector3d& hand, const DriveView& drive,
                        double force_scale_m_per_n, bool dragging) {
  ImDrawList* dl = ImGui::GetBackgroundDrawList();
  Eigen::Vector2f px;
  if (!camera.project(hand.cast<float>(), view_w, view_h, px)) return;
  const ImVec2 c(px.x(), px.y());
  const ImU32 hand_color = IM_COL32(120, 220, 255, 255);
  if (dragging) dl->AddCircleFilled(c, 9.0f, IM_COL32(120, 220, 255, 120));
  dl->AddCircle(c, 12.0f, hand_color, 24, 2.0f);
  if (drive.force_enabled && drive.force_n.norm() > 1e-3) {
    const Eigen::Vector3d tip = hand + force_scale_m_per_n * drive.force_n;
    Eigen::Vector2f pt;
    if (camera.project(tip.cast<float>(), view_w, view_h, pt)) {
      const ImU32 col = IM_COL32(255, 80, 200, 255);
      dl->AddLine(c, ImVec2(pt.x(), pt.y()), col, 3.0f);
      // arrow head
      const Eigen::Vector2f d = (pt - px).normalized() * 10.0f;
      const Eigen::Vector2f n(-d.y() * 0.5f, d.x() * 0.5f);
      dl->AddTriangleFilled(ImVec2(pt.x(), pt.y()),
                            ImVec2(pt.x() - d.x() + n.x(), pt.y() - d.y() + n.y()),
                            ImVec2(pt.x() - d.x() - n.x(), pt.y() - d.y() - n.y()), col);
    }
  }
}

namespace {

/// One form row: greyed out (and not sent) when the master's scheme does not take the field.
void field_row(const char* label, double& value, double max, bool enabled, const char* fmt) {
  if (!enabled) ImGui::BeginDisabled();
  ImGui::SetNextItemWidth(110.0f);
  ImGui::InputDouble(label, &value, 0.0, 0.0, fmt);
  value = std::clamp(std::isfinite(value) ? value : 0.0, 0.0, max);
  if (!enabled) ImGui::EndDisabled();
}

}  // namespace

std::uint32_t draw_drive_window(const DriveView& drive, double peak_force_n, TuningForm& form,
                                float view_h) {
  // below the overlay in the top-left corner: it grows downwards as the tuning form appears,
  // and stays inside a view at least 480 px high
  ImGui::SetNextWindowPos(ImVec2(10.0f, std::min(100.0f, 0.15f * view_h)), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowBgAlpha(0.75f);
  ImGui::Begin("Drive", nullptr,
               ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoSavedSettings);
  const double f = drive.force_enabled ? drive.force_n.norm() : 0.0;
  ImGui::Text("force %.2f N of %.0f N%s", f, peak_force_n,
              drive.force_age_s > 0.1 ? "  (no master)" : "");
  ImGui::ProgressBar(static_cast<float>(std::clamp(f / std::max(peak_force_n, 1e-9), 0.0, 1.0)),
                     ImVec2(240.0f, 0.0f));
  const Eigen::Vector3d& x = drive.position_m;
  ImGui::Text("hand (%.3f, %.3f, %.3f) m", x.x(), x.y(), x.z());
  ImGui::TextDisabled("drag the ring; arrows, PgUp/PgDn move it");

  std::uint32_t send = 0;
  if (!drive.have_status) {
    ImGui::TextDisabled("tuning: no master status yet");
  } else {
    const TuningStatus& s = drive.status;
    // the values in force: at the first status, and again after each answer (an applied request
    // shows its targets, a rejected one puts back what is in force)
    if (!form.loaded || s.request_seq() != form.answered) {
      form.answered = s.request_seq();
      form.master_stiffness_n_per_m = s.master_stiffness_n_per_m();
      form.master_damping_ns_per_m = s.master_damping_ns_per_m();
      form.force_gain = s.force_gain();
      form.slave_stiffness_n_per_m = s.slave_stiffness_n_per_m();
      form.forward_delay_ms = s.forward_delay_ms();
      form.backward_delay_ms = s.backward_delay_ms();
      form.loaded = true;
    }
    ImGui::Separator();
    ImGui::Text("tuning (%s)", s.scheme().c_str());
    if (!s.accepting()) {
      ImGui::TextColored(ImVec4(1.0f, 0.8f, 0.3f, 1.0f),
                         "the master does not accept tuning\n(start it with --accept-tuning)");
    } else {
      const std::uint32_t t = s.tunable();
      field_row("K_pm [N/m]", form.master_stiffness_n_per_m, s.max_master_stiffness_n_per_m(),
                t & TUNE_MASTER_STIFFNESS, "%.0f");
      field_row("B_m [N s/m]", form.master_damping_ns_per_m, s.max_master_damping_ns_per_m(),
                t & TUNE_MASTER_DAMPING, "%.2f");
      field_row("K_f", form.force_gain, s.max_force_gain(), t & TUNE_FORCE_GAIN, "%.2f");
      field_row("K_ps [N/m]", form.slave_stiffness_n_per_m, s.max_slave_stiffness_n_per_m(),
                t & TUNE_SLAVE_STIFFNESS, "%.0f");
      field_row("delay fwd [ms]", form.forward_delay_ms, s.max_delay_ms(), t & TUNE_FORWARD_DELAY,
                "%.1f");
      field_row("delay bwd [ms]", form.backward_delay_ms, s.max_delay_ms(), t & TUNE_BACKWARD_DELAY,
                "%.1f");
      field_row("ramp [s]", form.ramp_s, 10.0, true, "%.2f");
      if (ImGui::Button("Apply")) send = t;
      ImGui::SameLine();
      ImGui::Text("%llu applied, %llu rejected",
                  static_cast<unsigned long long>(s.accepted_count()),
                  static_cast<unsigned long long>(s.rejected_count()));
      if (s.request_seq() > 0) {
        ImGui::PushTextWrapPos(ImGui::GetCursorPosX() + 300.0f);
        ImGui::TextColored(
            s.accepted() ? ImVec4(0.5f, 0.9f, 0.5f, 1.0f) : ImVec4(1.0f, 0.45f, 0.45f, 1.0f), "%s",
            s.message().c_str());
        ImGui::PopTextWrapPos();
      }
    }
  }
  ImGui::End();
  return send;
}

}  // namespace teleop::viewer
