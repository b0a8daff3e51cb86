#pragma once
// "Did you mean": the known name closest to a mistyped one, for the refusals of unknown flags,
// options and command names.
#include <string>
#include <vector>

namespace teleop::config {

/// The candidate closest to `word` by edit distance (insertions, deletions, substitutions and
/// swaps of two neighbours; leading dashes ignored), or "" when none is close: at most 1 edit
/// for words of up to 4 characters, 2 up to 8, else 3. Ties go to the first candidate.
std::string closest_name(const std::string& word, const std::vector<std::string>& candidates);
/// " (did you mean 'X'?)" with X = closest_name(word, candidates), or "" when none is close.
std::string did_you_mean(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace teleop::config
