// The table of the master-side schemes: a name, a constructor and the scheme's own parameters
// each. A new scheme is a file pair in this folder and one line here (docs/control.md, "Adding
// a scheme"). The controller's parameter table joins the common parameters and each scheme's.
#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "client/control/bilateral_controller.hpp"
#include "client/control/schemes/force_position.hpp"
#include "client/control/schemes/model_mediated.hpp"
#include "client/control/schemes/position_position.hpp"
#include "client/control/schemes/tdpa.hpp"
#include "client/control/schemes/wave_variables.hpp"
#include "teleop/idl/Teleop.h"

namespace teleop::master {
namespace {

constexpr bool same_id(SchemeId id, std::uint8_t idl) {
  return static_cast<std::uint8_t>(id) == idl;
}
static_assert(same_id(SchemeId::kPositionPosition, SCHEME_POSITION_POSITION));
static_assert(same_id(SchemeId::kForcePosition, SCHEME_FORCE_POSITION));
static_assert(same_id(SchemeId::kWaveVariables, SCHEME_WAVE_VARIABLES));
static_assert(same_id(SchemeId::kTimeDomainPassivity, SCHEME_TIME_DOMAIN_PASSIVITY));
static_assert(same_id(SchemeId::kModelMediated, SCHEME_MODEL_MEDIATED));

struct Scheme {
  const char* name;
  std::unique_ptr<BilateralController> (*make)();
  /// The scheme's own parameters (the class's static parameters()).
  const std::vector<ControllerParam>& (*parameters)();
};

template <class Controller>
std::unique_ptr<BilateralController> make() {
  return std::make_unique<Controller>();
}

constexpr Scheme kSchemes[] = {
    {"position-position", &make<PositionPositionController>,
     &PositionPositionController::parameters},
    {"force-position", &make<ForcePositionController>, &ForcePositionController::parameters},
    {"wave-variables", &make<WaveVariablesController>, &WaveVariablesController::parameters},
    {"tdpa", &make<TimeDomainPassivityController>, &TimeDomainPassivityController::parameters},
    {"model-mediated", &make<ModelMediatedController>, &ModelMediatedController::parameters},
};

[[noreturn]] void refuse_scheme(const std::string& scheme) {
  std::string allowed;
  for (const Scheme& s : kSchemes) allowed += (allowed.empty() ? "" : ", ") + std::string(s.name);
  throw config::ConfigError("controller: scheme '" + scheme + "' is unknown (allowed: " + allowed +
                            ")");
}

}  // namespace

const std::vector<std::string>& controller_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const Scheme& s : kSchemes) n.emplace_back(s.name);
    return n;
  }();
  return names;
}

const std::vector<ControllerParam>& controller_param_table() {
  static const std::vector<ControllerParam> table = [] {
    std::vector<ControllerParam> all = common_controller_params();
    for (const Scheme& s : kSchemes) {
      for (ControllerParam d : s.parameters()) {
        d.scheme = s.name;
        all.push_back(std::move(d));
      }
    }
    return all;
  }();
  return table;
}

std::vector<ControllerParam> scheme_params(const std::string& scheme) {
  const std::vector<std::string>& names = controller_names();
  if (std::find(names.begin(), names.end(), scheme) == names.end()) refuse_scheme(scheme);
  std::vector<ControllerParam> own;
  for (const ControllerParam& d : controller_param_table()) {
    if (d.scheme == scheme) own.push_back(d);
  }
  return own;
}

std::unique_ptr<BilateralController> make_controller(const std::string& scheme) {
  for (const Scheme& s : kSchemes) {
    if (scheme == s.name) {
      auto controller = s.make();
      if (scheme != controller->name()) {
        throw config::ConfigError("controller: scheme table entry '" + scheme +
                                  "' makes a controller named '" + controller->name() + "'");
      }
      return controller;
    }
  }
  refuse_scheme(scheme);
}

}  // namespace teleop::master
