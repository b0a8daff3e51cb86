#include "server/node/ownership.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

namespace teleop::server {

namespace {
const char* or_unnamed(const char* name) { return name && *name ? name : "(unnamed)"; }
}  // namespace

const char* to_string(Admit a) {
  switch (a) {
    case Admit::kOwner:
      return "owner";
    case Admit::kAcquired:
      return "acquired";
    case Admit::kTakenOver:
      return "taken over";
    case Admit::kReleased:
      return "released";
    case Admit::kRefused:
      return "refused";
    case Admit::kIgnored:
      return "ignored";
  }
  return "?";
}

std::uint32_t Ownership::owner_session(std::int64_t now_ns) const {
  if (!owned_ || now_ns - last_ns_ > timeout_ns_) return 0;
  return session_;
}

void Ownership::take(const WriterId& writer, std::uint32_t session, const char* name,
                     std::uint64_t seq, std::int64_t now_ns) {
  owned_ = true;
  owner_ = writer;
  session_ = session;
  std::snprintf(owner_name_.data(), owner_name_.size(), "%s", or_unnamed(name));
  last_ns_ = now_ns;
  first_seq_ = seq;
  owner_received_ = 1;
  ++changes_;
  // a writer that owns the slave is no longer one that was refused
  for (std::size_t i = 0; i < std::min(refused_count_, refused_writers_.size()); ++i) {
    if (refused_writers_[i] == writer) refused_writers_[i] = WriterId{};
  }
}

bool Ownership::first_refusal_of(const WriterId& writer) {
  const std::size_t n = std::min(refused_count_, refused_writers_.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (refused_writers_[i] == writer) return false;
  }
  refused_writers_[refused_count_ % refused_writers_.size()] = writer;
  ++refused_count_;
  return true;
}

Admit Ownership::admit(const WriterId& writer, std::uint32_t session, const char* name,
                       std::uint64_t seq, bool release, std::int64_t now_ns) {
  notable_ = false;
  tags_ = {};
  if (owned_ && writer == owner_) {
    last_ns_ = now_ns;
    if (!release) {
      ++owner_received_;
      return Admit::kOwner;
    }
    owned_ = false;
    notable_ = true;
    tags_.session = session_;
    std::snprintf(message_.data(), message_.size(),
                  "master '%s' (session 0x%08x) released the slave after %llu commands",
                  owner_name_.data(), session_, static_cast<unsigned long long>(owner_received_));
    return Admit::kReleased;
  }
  if (release) return Admit::kIgnored;  // a master that does not own it has nothing to give up
  if (!owned_) {
    take(writer, session, name, seq, now_ns);
    notable_ = true;
    tags_.session = session_;
    std::snprintf(message_.data(), message_.size(), "master '%s' (session 0x%08x) owns the slave",
                  owner_name_.data(), session_);
    return Admit::kAcquired;
  }
  const std::int64_t silent_ns = now_ns - last_ns_;
  if (silent_ns > timeout_ns_) {
    char previous[sizeof(owner_name_)];
    std::memcpy(previous, owner_name_.data(), sizeof(previous));
    const std::uint32_t previous_session = session_;
    take(writer, session, name, seq, now_ns);
    notable_ = true;
    tags_.session = session_;
    tags_.other_session = previous_session;
    std::snprintf(message_.data(), message_.size(),
                  "master '%s' (session 0x%08x) took the slave over from '%s' (session 0x%08x), "
                  "silent for %.0f ms",
                  owner_name_.data(), session_, previous, previous_session,
                  static_cast<double>(silent_ns) * 1e-6);
    return Admit::kTakenOver;
  }
  ++refused_;
  if (first_refusal_of(writer)) {
    notable_ = true;
    tags_.session = session;
    tags_.other_session = session_;
    std::snprintf(message_.data(), message_.size(),
                  "refused commands from master '%s' (session 0x%08x): the slave is owned by "
                  "'%s' (session 0x%08x)",
                  or_unnamed(name), session, owner_name_.data(), session_);
  }
  return Admit::kRefused;
}

}  // namespace teleop::server
