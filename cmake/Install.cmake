# The installed library, HybridTree::hybridtree: the same objects as hybridtree_core, shared by
# default (HYBRIDTREE_SHARED=OFF: static), exporting only the embedding API (runtime/api.hpp,
# installed as <hybridtree/api.hpp>, which needs nothing but the standard library). Embree,
# OpenMesh, nlohmann-json, GLM and TBB stay private: the package config finds them only for the
# static library, whose consumers link them too.
#   cmake --install build --prefix P   installs lib/, include/hybridtree/, bin/hybridtree,
#   lib/cmake/HybridTree/ and, with the Python module built, lib/python3.X/site-packages/.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

if(HYBRIDTREE_SHARED)
  add_library(hybridtree_lib SHARED $<TARGET_OBJECTS:hybridtree_objects>)
else()
  add_library(hybridtree_lib STATIC $<TARGET_OBJECTS:hybridtree_objects>)
endif()
add_library(HybridTree::hybridtree ALIAS hybridtree_lib)
set_target_properties(hybridtree_lib PROPERTIES OUTPUT_NAME hybridtree EXPORT_NAME hybridtree
  VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR})
# The public header includes only the standard library: its folder is the only include path a
# consumer gets. The build tree holds a copy laid out as installed (configure_file copies it again
# whenever runtime/api.hpp changes), so the Python module includes <hybridtree/api.hpp> too.
configure_file(${PROJECT_SOURCE_DIR}/runtime/api.hpp ${PROJECT_BINARY_DIR}/include/hybridtree/api.hpp COPYONLY)
target_include_directories(hybridtree_lib INTERFACE
  $<BUILD_INTERFACE:${PROJECT_BINARY_DIR}/include>
  $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
target_compile_features(hybridtree_lib INTERFACE cxx_std_20)
target_link_libraries(hybridtree_lib PRIVATE ${HYBRIDTREE_PUBLIC_DEPS} ${HYBRIDTREE_PRIVATE_DEPS})

install(TARGETS hybridtree_lib EXPORT HybridTreeTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(FILES ${PROJECT_SOURCE_DIR}/runtime/api.hpp DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/hybridtree)
install(EXPORT HybridTreeTargets NAMESPACE HybridTree:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/HybridTree)
set(HYBRIDTREE_CONFIG_SHARED ${HYBRIDTREE_SHARED})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/HybridTreeConfig.cmake.in
  ${PROJECT_BINARY_DIR}/HybridTreeConfig.cmake INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/HybridTree)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/HybridTreeConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/HybridTreeConfig.cmake ${PROJECT_BINARY_DIR}/HybridTreeConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/HybridTree)
