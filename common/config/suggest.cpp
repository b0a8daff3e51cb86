#include "common/config/suggest.hpp"

#include <algorithm>
#include <cstddef>

namespace teleop::config {

namespace {
/// Optimal string alignment distance (Levenshtein plus swaps of two neighbours).
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[a.size()][b.size()];
}

/// The characters of a name that count: "--levle" and "levle" compare alike.
std::string bare_name(const std::string& s) {
  std::size_t start = 0;
  while (start < s.size() && s[start] == '-') ++start;
  return s.substr(start);
}
}  // namespace

std::string closest_name(const std::string& word, const std::vector<std::string>& candidates) {
  const std::string w = bare_name(word);
  if (w.empty()) return "";
  const std::size_t allowed = w.size() <= 4 ? 1 : (w.size() <= 8 ? 2 : 3);
  std::string best;
  std::size_t best_d = allowed + 1;
  for (const std::string& c : candidates) {
    const std::size_t d = edit_distance(w, bare_name(c));
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  return best;
}

std::string did_you_mean(const std::string& word, const std::vector<std::string>& candidates) {
  const std::string best = closest_name(word, candidates);
  return best.empty() ? "" : " (did you mean '" + best + "'?)";
}

}  // namespace teleop::config
