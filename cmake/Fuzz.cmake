# HYBRIDTREE_FUZZ=ON: the libFuzzer targets of fuzz/ (fuzz_scene, fuzz_mesh_off, ...), with
# AddressSanitizer and UndefinedBehaviorSanitizer. libFuzzer comes with clang only (Debian 12:
# clang 14 and libclang-rt-14-dev), so configure a build folder of its own with clang:
#   CC=clang CXX=clang++ cmake -S . -B build-fuzz -DHYBRIDTREE_FUZZ=ON (tools/fuzz.sh does it).
# Everything compiled here gets the coverage instrumentation (fuzzer-no-link) and the sanitizers;
# only the fuzz targets link libFuzzer's driver (fuzz/CMakeLists.txt). Undefined behaviour aborts
# instead of printing and going on, so libFuzzer records it as a crash.
option(HYBRIDTREE_FUZZ "Build the libFuzzer targets of fuzz/ (clang only)" OFF)
if(HYBRIDTREE_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "HYBRIDTREE_FUZZ=ON needs clang (libFuzzer is part of clang), not "
      "${CMAKE_CXX_COMPILER_ID}: configure a fresh build folder with CC=clang CXX=clang++ "
      "(tools/fuzz.sh does)")
  endif()
  if(HYBRIDTREE_SANITIZE)
    message(FATAL_ERROR "HYBRIDTREE_FUZZ=ON already builds with the sanitizers: leave HYBRIDTREE_SANITIZE off")
  endif()
  set(HYBRIDTREE_FUZZ_SANITIZERS address,undefined)
  add_compile_options(-fsanitize=fuzzer-no-link,${HYBRIDTREE_FUZZ_SANITIZERS}
    -fno-sanitize-recover=undefined -fno-omit-frame-pointer -g)
  add_link_options(-fsanitize=${HYBRIDTREE_FUZZ_SANITIZERS})
  # The fuzz targets add -fsanitize=fuzzer at link time (libFuzzer's main()).
  set(HYBRIDTREE_FUZZ_LINK_FLAGS -fsanitize=fuzzer,${HYBRIDTREE_FUZZ_SANITIZERS})
endif()
