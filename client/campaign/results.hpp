#pragma once
// One run of a campaign and its row of the results table.
//
// The row is the run's parameters followed by what the session measured (the figures of the
// session summary: verdict and its reason, stability, errors, transparency, energy, faults,
// channels; the groups the campaign's `measure:` names). Numbers are written in the shortest
// form that reads back to the same double (std::to_chars), "nan" where a figure was not
// measured and "inf" for an unbounded margin, so a row is the same bytes wherever it is made.
#include <string>

#include "client/campaign/campaign.hpp"

namespace teleop::campaign {

/// The header line of the results table (no newline).
std::string results_header(const Campaign& c);
/// The parameter cells of run `p` (the first columns of its row; no newline).
std::string parameter_cells(const Campaign& c, const RunParams& p);

/// Runs `p` in-process on the simulated clock (client/sim/loopback_session.hpp with the
/// server's world as the slave) and returns its whole row (no newline). A run that throws
/// (a world that cannot be built) gives a row with verdict "error" and the message as reason.
std::string run_one(const Campaign& c, const RunParams& p);

/// The run id as it names files and leads a row: the id zero-padded to 7 digits.
std::string run_name(std::size_t id);

}  // namespace teleop::campaign
