# Every dependency comes from Debian's packages (tools/setup.sh installs them); nothing is
# downloaded at build time.
find_package(TBB REQUIRED)
find_package(embree 3 REQUIRED)
find_package(glm REQUIRED)
find_package(OpenMesh REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(CLI11 REQUIRED)
if(HYBRIDTREE_TESTS)
  find_package(GTest REQUIRED)
endif()
if(HYBRIDTREE_BENCH)
  find_package(benchmark REQUIRED)
endif()
# OpenMesh's package config names its targets but not its include folder on Debian.
if(TARGET OpenMeshCore)
  set_property(TARGET OpenMeshCore APPEND PROPERTY INTERFACE_COMPILE_DEFINITIONS _USE_MATH_DEFINES)
endif()
