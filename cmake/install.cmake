# Install rules and the CMake package (included from the top-level CMakeLists.txt when
# STIFFBENCH_INSTALL is on):
#   <prefix>/bin/stiffbench
#   <prefix>/lib/libstiffbench_{core,models,integrators,experiments,cli}.a
#   <prefix>/include/stiffbench/stiffbench.hpp        the public umbrella header
#   <prefix>/include/stiffbench/{core,models,integrators,experiments,cli}/...   every header
#   <prefix>/share/stiffbench/plots/*.gp              gnuplot scripts (the binary looks here)
#   <prefix>/lib/cmake/stiffbench/stiffbenchConfig.cmake, ...ConfigVersion.cmake, ...Targets.cmake
# A consumer writes find_package(stiffbench REQUIRED) and links stiffbench::stiffbench (or the
# finer stiffbench::core, ::models, ::integrators, ::experiments, ::cli).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(_sb_libs stiffbench_core stiffbench_models stiffbench_integrators stiffbench_experiments
             stiffbench_cli)
set_target_properties(stiffbench_core PROPERTIES EXPORT_NAME core)
set_target_properties(stiffbench_models PROPERTIES EXPORT_NAME models)
set_target_properties(stiffbench_integrators PROPERTIES EXPORT_NAME integrators)
set_target_properties(stiffbench_experiments PROPERTIES EXPORT_NAME experiments)
set_target_properties(stiffbench_cli PROPERTIES EXPORT_NAME cli)

install(TARGETS ${_sb_libs} stiffbench_all EXPORT stiffbenchTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(TARGETS stiffbench RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(FILES ${STIFFBENCH_PLOT_SCRIPTS} DESTINATION ${CMAKE_INSTALL_DATADIR}/stiffbench/plots)

set(_sb_incdir ${CMAKE_INSTALL_INCLUDEDIR}/stiffbench)
# integrators/reference/sundials/ is internal (its headers include SUNDIALS'): not installed.
foreach(_layer core models integrators experiments cli)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${_layer}/ DESTINATION ${_sb_incdir}/${_layer}
          FILES_MATCHING PATTERN "*.hpp" REGEX "/reference/sundials(/|$)" EXCLUDE)
endforeach()
install(FILES ${PROJECT_SOURCE_DIR}/include/stiffbench/stiffbench.hpp DESTINATION ${_sb_incdir})
install(FILES ${PROJECT_BINARY_DIR}/generated/experiments/build_info.hpp
        DESTINATION ${_sb_incdir}/experiments)
# Installed headers include each other as "stiffbench/core/..." (rewritten here), so only
# <prefix>/include is on a consumer's include path: no top-level core/, models/, experiments/, cli/.
install(CODE "set(DIR \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/${_sb_incdir}\")
              include(\"${PROJECT_SOURCE_DIR}/cmake/rewrite_includes.cmake\")")

set(_sb_cmakedir ${CMAKE_INSTALL_LIBDIR}/cmake/stiffbench)
install(EXPORT stiffbenchTargets NAMESPACE stiffbench:: DESTINATION ${_sb_cmakedir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/stiffbenchConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/stiffbenchConfig.cmake
                              INSTALL_DESTINATION ${_sb_cmakedir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/stiffbenchConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/stiffbenchConfig.cmake
              ${PROJECT_BINARY_DIR}/stiffbenchConfigVersion.cmake
        DESTINATION ${_sb_cmakedir})
