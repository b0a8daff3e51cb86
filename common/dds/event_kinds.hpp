#pragma once
// The event kinds of teleop/events once: the physics loop's sim::EventKind (and EventSubject) is
// checked here, value by value, against the EVENT_* constants of idl/Teleop.idl, and
// event_kind_name() is the one word for each kind that every observer (monitor, viewer, bridge,
// recordings) shows.
// Header-only.
#include <cstdint>

#include "common/sim/events.hpp"
#include "teleop/idl/Teleop.h"

namespace teleop::dds {

namespace detail {
constexpr bool same_kind(sim::EventKind k, std::uint8_t idl) {
  return static_cast<std::uint8_t>(k) == idl;
}
}  // namespace detail

static_assert(detail::same_kind(sim::EventKind::kInfo, EVENT_INFO));
static_assert(detail::same_kind(sim::EventKind::kContactBegin, EVENT_CONTACT_BEGIN));
static_assert(detail::same_kind(sim::EventKind::kContactEnd, EVENT_CONTACT_END));
static_assert(detail::same_kind(sim::EventKind::kWatchdog, EVENT_WATCHDOG));
static_assert(detail::same_kind(sim::EventKind::kFault, EVENT_FAULT));
static_assert(detail::same_kind(sim::EventKind::kModeChange, EVENT_MODE_CHANGE));
static_assert(detail::same_kind(sim::EventKind::kCommandRejected, EVENT_COMMAND_REJECTED));
static_assert(detail::same_kind(sim::EventKind::kLimit, EVENT_LIMIT));
static_assert(detail::same_kind(sim::EventKind::kSafety, EVENT_SAFETY));
static_assert(detail::same_kind(sim::EventKind::kOwnership, EVENT_OWNERSHIP));
static_assert(detail::same_kind(sim::EventKind::kTuning, EVENT_TUNING));
static_assert(static_cast<std::uint8_t>(sim::EventSubject::kNone) == EVENT_SUBJECT_NONE);
static_assert(static_cast<std::uint8_t>(sim::EventSubject::kPositionGain) ==
              EVENT_SUBJECT_POSITION_GAIN);

/// The word observers show for an event kind ("info" for an unknown one).
constexpr const char* event_kind_name(std::uint8_t kind) {
  switch (kind) {
    case EVENT_CONTACT_BEGIN:
      return "contact-begin";
    case EVENT_CONTACT_END:
      return "contact-end";
    case EVENT_WATCHDOG:
      return "watchdog";
    case EVENT_FAULT:
      return "FAULT";
    case EVENT_MODE_CHANGE:
      return "mode";
    case EVENT_COMMAND_REJECTED:
      return "rejected";
    case EVENT_LIMIT:
      return "limit";
    case EVENT_SAFETY:
      return "safety";
    case EVENT_OWNERSHIP:
      return "ownership";
    case EVENT_TUNING:
      return "tuning";
    default:
      return "info";
  }
}

}  // namespace teleop::dds
