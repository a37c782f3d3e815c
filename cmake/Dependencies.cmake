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
# OpenVDB (Debian's libopenvdb-dev), optional and for bench/ only: the peer benchmark
# bench/vdb_peer_bench.cpp builds when it is found. Found by hand rather than through the
# FindOpenVDB.cmake Debian ships under lib/cmake/OpenVDB/: that module sits off CMake's module
# path, brings a FindTBB.cmake of its own and requires Boost's iostreams component.
if(HYBRIDTREE_BENCH)
  find_path(HYBRIDTREE_OPENVDB_INCLUDE_DIR openvdb/openvdb.h)
  find_library(HYBRIDTREE_OPENVDB_LIBRARY openvdb)
  find_package(Imath CONFIG QUIET)
  if(HYBRIDTREE_OPENVDB_INCLUDE_DIR AND HYBRIDTREE_OPENVDB_LIBRARY AND TARGET Imath::Imath)
    add_library(hybridtree_openvdb INTERFACE IMPORTED)
    # SYSTEM: OpenVDB's headers are not held to our warnings.
    set_target_properties(hybridtree_openvdb PROPERTIES
      INTERFACE_SYSTEM_INCLUDE_DIRECTORIES "${HYBRIDTREE_OPENVDB_INCLUDE_DIR}"
      INTERFACE_LINK_LIBRARIES "${HYBRIDTREE_OPENVDB_LIBRARY};Imath::Imath;TBB::tbb")
    message(STATUS "OpenVDB: ${HYBRIDTREE_OPENVDB_LIBRARY}; the peer benchmark (bench/vdb_peer_bench.cpp) is built")
  else()
    message(STATUS "OpenVDB not found (Debian: libopenvdb-dev, which tools/setup.sh installs): "
      "the peer benchmark bench/vdb_peer_bench.cpp is left out")
  endif()
endif()
