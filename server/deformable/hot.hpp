#pragma once
// Internal: the attributes of the deformable body's hot loops (server/deformable/). Not part of
// the deformable API.
//
// TELEOP_HOT_CLONES: the function is compiled twice, for x86-64-v3 (AVX2, FMA) and for the
// baseline, and the loader picks the one the CPU supports (GCC function multi-versioning), so
// the binary still runs on any x86-64. Not under the sanitizers: their instrumentation of the
// ifunc resolvers runs before the sanitizer runtime is initialised and crashes the program at
// load time.
//
// TELEOP_ALWAYS_INLINE: for the helpers of the hot functions, inlined into every clone, so each
// copy keeps the instruction set of its caller (a call to a separate baseline copy would lose
// AVX2 and FMA). A helper used by hot functions of several files lives in a header with it.

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && \
    !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#define TELEOP_HOT_CLONES \
  __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define TELEOP_HOT_CLONES
#endif

#if defined(__GNUC__)
#define TELEOP_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define TELEOP_ALWAYS_INLINE inline
#endif
