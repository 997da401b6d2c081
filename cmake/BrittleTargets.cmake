# Per-target flags: warnings, sanitizers. Never global.
function(brittle_target_flags target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow=local)
  # In a unity batch every source but the first reads as a header to GCC, which then flags a class
  # holding a file-local (anonymous-namespace) type; that is what the file meant.
  if(CMAKE_UNITY_BUILD)
    target_compile_options(${target} PRIVATE -Wno-subobject-linkage)
  endif()
  # The public headers are C++20 (defaulted comparisons): consumers get the standard from the targets.
  target_compile_features(${target} PUBLIC cxx_std_20)
  # One version for every module and tool (packs record it as "generator").
  target_compile_definitions(${target} PRIVATE BRITTLE_VERSION="${PROJECT_VERSION}")
  # Eigen blocks its products by cache sizes it would read from the CPU, and another blocking
  # rounds otherwise: fixed sizes instead, the same as brittle::pinEigenBlocking's, so that packs
  # and fractures are the same bits on every machine (brittle/core/EigenBlocking.h).
  target_compile_definitions(${target} PRIVATE EIGEN_NO_CPUID EIGEN_DEFAULT_L1_CACHE_SIZE=32768
                                               EIGEN_DEFAULT_L2_CACHE_SIZE=262144 EIGEN_DEFAULT_L3_CACHE_SIZE=2097152)
  if(BRITTLE_SANITIZE)
    # UBSan without four checks that AddressSanitizer's shadow memory already covers or that x86-64
    # does not need: null (a null access faults and ASan reports it with its stack), object-size and
    # pointer-overflow (ASan's redzones catch the out-of-bounds access itself), and alignment
    # (Eigen's allocations are aligned by hand here, and x86-64 loads need no alignment but for the
    # aligned SIMD loads, which fault). They made up ~46 % of an instrumented unit's compile (the
    # runtime's first unity batch: 93 s of CPU with them, 50 s without, 50 s with ASan alone,
    # 33 s uninstrumented). Signed overflow, shifts, bounds, enums, bools, vptr, unreachable and
    # the rest stay on: those ASan cannot see.
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
      -fno-sanitize=null,object-size,pointer-overflow,alignment -fno-sanitize-recover=undefined)
    # PUBLIC: a program that loads a sanitized library must link the sanitizer runtime itself,
    # a consumer of the installed package too.
    target_link_options(${target} PUBLIC -fsanitize=address,undefined)
    # One Eigen allocation scheme in every unit, with or without instrumentation (the CGAL units
    # of precompute go without it): the handmade aligned one, which Eigen uses under ASan anyway.
    target_compile_definitions(${target} PUBLIC EIGEN_MALLOC_ALREADY_ALIGNED=0)
  endif()
endfunction()

# Link options a final executable needs when the sanitizers are on.
function(brittle_executable_flags target)
  brittle_target_flags(${target})
  if(BRITTLE_SANITIZE)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()
