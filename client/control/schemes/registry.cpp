// The table of the master-side schemes: a name and the scheme's class, whose static members
// give the constructor, its own parameters, its traits (what the shared code asks of it,
// client/control/scheme_traits.hpp) and its variants. A new scheme is a file pair in this folder
// and one line here (docs/control.md, "Adding a scheme"). The controller's parameter table joins
// the common parameters and each scheme's.
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
  /// What the shared code asks of it (the class's static traits()).
  SchemeTraits (*traits)(const ControllerParams&);
  /// Its labels with some parameters fixed (the class's static variants(); none: its name).
  const std::vector<SchemeVariant>& (*variants)();
};

template <class Controller>
std::unique_ptr<BilateralController> make() {
  return std::make_unique<Controller>();
}

/// The table's line of the scheme `name`, implemented by `Controller`.
template <class Controller>
constexpr Scheme entry(const char* name) {
  return {name, &make<Controller>, &Controller::parameters, &Controller::traits,
          &Controller::variants};
}

constexpr Scheme kSchemes[] = {
    entry<PositionPositionController>("position-position"),
    entry<ForcePositionController>("force-position"),
    entry<WaveVariablesController>("wave-variables"),
    entry<TimeDomainPassivityController>("tdpa"),
    entry<ModelMediatedController>("model-mediated"),
};

[[noreturn]] void refuse(const std::string& scheme, const std::vector<std::string>& names) {
  std::string allowed;
  for (const std::string& n : names) allowed += (allowed.empty() ? "" : ", ") + n;
  throw config::ConfigError("controller: scheme '" + scheme + "' is unknown (allowed: " + allowed +
                            ")");
}

[[noreturn]] void refuse_scheme(const std::string& scheme) { refuse(scheme, controller_names()); }

/// One label of scheme_variant_labels(): the scheme and what the label sets.
struct Label {
  std::string label;
  const Scheme* scheme;
  void (*apply)(ControllerParams&);  ///< nullptr: the scheme's name, nothing set
};

const std::vector<Label>& labels() {
  static const std::vector<Label> all = [] {
    std::vector<Label> v;
    for (const Scheme& s : kSchemes) {
      if (s.variants().empty()) v.push_back({s.name, &s, nullptr});
      for (const SchemeVariant& var : s.variants()) v.push_back({var.label, &s, var.apply});
    }
    return v;
  }();
  return all;
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

SchemeTraits scheme_traits(const ControllerParams& p) {
  for (const Scheme& s : kSchemes) {
    if (p.scheme == s.name) return s.traits(p);
  }
  refuse_scheme(p.scheme);
}

SchemeTraits scheme_traits(const std::string& scheme) {
  ControllerParams p;
  p.scheme = scheme;
  return scheme_traits(p);
}

const std::vector<std::string>& scheme_variant_labels() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const Label& l : labels()) n.push_back(l.label);
    return n;
  }();
  return names;
}

void apply_scheme_variant(const std::string& label, ControllerParams& p) {
  for (const Label& l : labels()) {
    if (l.label != label) continue;
    p.scheme = l.scheme->name;
    if (l.apply) l.apply(p);
    return;
  }
  refuse(label, scheme_variant_labels());
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
