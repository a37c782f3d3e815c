# HYBRIDTREE_SANITIZE=ON: every target (library, CLI, tests, benchmarks) compiled and linked
# with AddressSanitizer and UndefinedBehaviorSanitizer. Undefined behaviour aborts instead of
# printing and going on, so a finding fails its test. Use a build folder of its own
# (tools/check_sanitize.sh); the Release build is unchanged when the option is off.
option(HYBRIDTREE_SANITIZE "Build everything with AddressSanitizer and UndefinedBehaviorSanitizer" OFF)
if(HYBRIDTREE_SANITIZE)
  set(HYBRIDTREE_SANITIZE_FLAGS -fsanitize=address,undefined -fno-omit-frame-pointer
    -fno-sanitize-recover=undefined)
  # GCC's manual warns that the sanitizers raise the rate of false -Wmaybe-uninitialized
  # warnings; here they fire inside OpenMesh's and libstdc++'s headers (PropertyT::push_back).
  # The Release build keeps the warning.
  add_compile_options(${HYBRIDTREE_SANITIZE_FLAGS} -Wno-maybe-uninitialized)
  add_link_options(${HYBRIDTREE_SANITIZE_FLAGS})
  # The tests' one switch for the sanitized build (tests/support/test_support.hpp kSanitized).
  add_compile_definitions(HYBRIDTREE_SANITIZED=1)
endif()
