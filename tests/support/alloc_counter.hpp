#pragma once
// Proves that a hot path does not allocate. Linking tests/support/alloc_counter.cpp into a
// test executable replaces global operator new/delete and malloc/calloc/realloc with
// counting versions. Inside a NoAllocScope every allocation on this thread is counted (and,
// when EIGEN_RUNTIME_NO_MALLOC is defined, Eigen's own check is switched on too).
//
//   teleop::test::NoAllocScope scope;
//   step(model, state, input, dt);
//   EXPECT_EQ(scope.allocations(), 0u);
#include <cstddef>
#include <cstdint>

namespace teleop::test {

/// Allocations made on the calling thread while counting was active.
std::uint64_t thread_allocations();

class NoAllocScope {
 public:
  NoAllocScope();
  ~NoAllocScope();
  NoAllocScope(const NoAllocScope&) = delete;
  NoAllocScope& operator=(const NoAllocScope&) = delete;
  /// Allocations seen since this scope began.
  std::uint64_t allocations() const;

 private:
  std::uint64_t start_;
  bool prev_active_;
};

}  // namespace teleop::test
