# The installable libraries and their packaging, included by the top-level
# CMakeLists.txt once every module is added:
#
#   libshortcrust         the core (core/shortcrust.h), target shortcrust_core
#   libshortcrust-client  the client library (clients/shortcrust_client.h)
#                         with the protocol codec and the file module
#                         inside, target shortcrust_client
#
# both shared (SONAME libshortcrust.so.0, libshortcrust-client.so.0) unless
# SC_SHARED is OFF, then static archives of the same names. Each is built
# from the objects of the module libraries (sc_core; sc_client, sc_proto,
# sc_files), which the project's own programs and tests keep linking
# statically: nothing is compiled twice. The module libraries are therefore
# position-independent, and built -fvisibility=hidden with their public
# header forced in under default visibility (cmake/*-visibility.h), so that
# a shared library exports its C API and nothing else; a version script
# (cmake/*.map) also hides what the C++ headers mark visible.
#
# `cmake --install` puts in the prefix the programs, the libraries, the two
# headers, shortcrust.pc and shortcrust-client.pc, the CMake package
# (find_package(shortcrust) gives shortcrust::core and shortcrust::client)
# and the systemd units. Components: Runtime (programs, shared libraries,
# units) and Development (headers, archives, link names, .pc, CMake files).

include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

option(SC_SHARED
       "Build the installed libraries (libshortcrust, libshortcrust-client) shared; OFF: static archives"
       ON)
if(SC_SHARED)
  set(sc_lib_type SHARED)
else()
  set(sc_lib_type STATIC)
endif()

# Everything that ends up in an installed library.
foreach(module sc_core sc_client sc_proto sc_files)
  if(TARGET ${module})
    set_target_properties(${module} PROPERTIES
      POSITION_INDEPENDENT_CODE ON
      C_VISIBILITY_PRESET hidden
      CXX_VISIBILITY_PRESET hidden
      VISIBILITY_INLINES_HIDDEN ON)
  endif()
endforeach()

set(sc_exported)
set(sc_linker_checks)
if(NOT SC_SANITIZE)
  # Every symbol the library uses is defined in it or in a library it names.
  # (The sanitizers' run-times come with the program, not the library.)
  set(sc_linker_checks -Wl,--no-undefined)
endif()

if(TARGET sc_core)
  target_compile_options(sc_core PRIVATE
    "SHELL:-include ${CMAKE_CURRENT_LIST_DIR}/core-visibility.h")
  # What the core links (CGAL, threads, TBB when found), for the library.
  # Imported targets are seen only in the directory that found them: find
  # the same packages here (the cache makes it quick).
  find_package(CGAL REQUIRED QUIET)
  find_package(TBB QUIET)
  get_target_property(sc_core_deps sc_core INTERFACE_LINK_LIBRARIES)

  add_library(shortcrust_core ${sc_lib_type} $<TARGET_OBJECTS:sc_core>)
  add_library(shortcrust::core ALIAS shortcrust_core)
  target_link_libraries(shortcrust_core PRIVATE ${sc_core_deps})
  target_include_directories(shortcrust_core INTERFACE
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/core>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  set_target_properties(shortcrust_core PROPERTIES
    OUTPUT_NAME shortcrust
    EXPORT_NAME core
    LINKER_LANGUAGE CXX
    VERSION ${PROJECT_VERSION}
    SOVERSION 0)
  if(SC_SHARED)
    target_link_options(shortcrust_core PRIVATE ${sc_linker_checks}
      -Wl,--version-script=${CMAKE_CURRENT_LIST_DIR}/shortcrust.map)
    set_property(TARGET shortcrust_core APPEND PROPERTY LINK_DEPENDS
                 ${CMAKE_CURRENT_LIST_DIR}/shortcrust.map)
  endif()
  list(APPEND sc_exported shortcrust_core)
endif()

if(TARGET sc_client)
  target_compile_options(sc_client PRIVATE
    "SHELL:-include ${CMAKE_CURRENT_LIST_DIR}/client-visibility.h")

  add_library(shortcrust_client ${sc_lib_type}
    $<TARGET_OBJECTS:sc_client> $<TARGET_OBJECTS:sc_proto>
    $<TARGET_OBJECTS:sc_files>)
  add_library(shortcrust::client ALIAS shortcrust_client)
  target_link_libraries(shortcrust_client PRIVATE m)
  target_include_directories(shortcrust_client INTERFACE
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/clients>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  set_target_properties(shortcrust_client PROPERTIES
    OUTPUT_NAME shortcrust-client
    EXPORT_NAME client
    LINKER_LANGUAGE C
    VERSION ${PROJECT_VERSION}
    SOVERSION 0)
  if(SC_SHARED)
    target_link_options(shortcrust_client PRIVATE ${sc_linker_checks}
      -Wl,--version-script=${CMAKE_CURRENT_LIST_DIR}/shortcrust-client.map)
    set_property(TARGET shortcrust_client APPEND PROPERTY LINK_DEPENDS
                 ${CMAKE_CURRENT_LIST_DIR}/shortcrust-client.map)
  endif()
  list(APPEND sc_exported shortcrust_client)
endif()

# --- Installation -----------------------------------------------------------

foreach(program shortcrust shortcrustd shortcrust-load)
  if(TARGET ${program})
    install(TARGETS ${program}
            RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT Runtime)
  endif()
endforeach()
if(EXISTS ${PROJECT_SOURCE_DIR}/daemon/shortcrustd.service AND
   TARGET shortcrustd)
  install(FILES ${PROJECT_SOURCE_DIR}/daemon/shortcrustd.service
                ${PROJECT_SOURCE_DIR}/daemon/shortcrustd.socket
          DESTINATION lib/systemd/system COMPONENT Runtime)
endif()

if(NOT sc_exported)
  return()
endif()

install(TARGETS ${sc_exported} EXPORT shortcrustTargets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT Runtime
                NAMELINK_COMPONENT Development
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT Development
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT Runtime
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
if(TARGET shortcrust_core)
  install(FILES ${PROJECT_SOURCE_DIR}/core/shortcrust.h
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT Development)
endif()
if(TARGET shortcrust_client)
  install(FILES ${PROJECT_SOURCE_DIR}/clients/shortcrust_client.h
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT Development)
endif()

# CMake package: shortcrustConfig.cmake, its version file and the targets.
set(sc_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/shortcrust)
set(SC_PACKAGE_HAS_CORE FALSE)
if(TARGET shortcrust_core)
  set(SC_PACKAGE_HAS_CORE TRUE)
endif()
set(SC_CORE_WITH_TBB FALSE)
if(TARGET TBB::tbb)
  set(SC_CORE_WITH_TBB TRUE)
endif()
install(EXPORT shortcrustTargets NAMESPACE shortcrust::
        DESTINATION ${sc_cmake_dir} FILE shortcrustTargets.cmake
        COMPONENT Development)
configure_package_config_file(
  ${CMAKE_CURRENT_LIST_DIR}/shortcrustConfig.cmake.in
  ${PROJECT_BINARY_DIR}/package/shortcrustConfig.cmake
  INSTALL_DESTINATION ${sc_cmake_dir})
# SOVERSION 0 promises the same ABI through 0.x, and so does this.
write_basic_package_version_file(
  ${PROJECT_BINARY_DIR}/package/shortcrustConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMajorVersion)
install(FILES ${PROJECT_BINARY_DIR}/package/shortcrustConfig.cmake
              ${PROJECT_BINARY_DIR}/package/shortcrustConfigVersion.cmake
        DESTINATION ${sc_cmake_dir} COMPONENT Development)

# pkg-config files. The prefix is the one installed to (cmake --install
# --prefix may change it), so they are written at install time; the rest
# is known now.
foreach(dir LIBDIR INCLUDEDIR)
  if(IS_ABSOLUTE "${CMAKE_INSTALL_${dir}}")
    set(SC_PC_${dir} "${CMAKE_INSTALL_${dir}}")
  else()
    set(SC_PC_${dir} "\${prefix}/${CMAKE_INSTALL_${dir}}")
  endif()
endforeach()
# What a program needs besides the library when it links the static
# archive (pkg-config --static); the shared libraries name their own.
set(sc_pc_core_requires gmp mpfr)
set(sc_pc_core_libs)
if(TARGET TBB::tbb)
  list(APPEND sc_pc_core_requires tbb)
  list(APPEND sc_pc_core_libs -ltbbmalloc)
endif()
list(APPEND sc_pc_core_libs -lstdc++ -lm -pthread)
if(SC_SHARED)
  # A program linking the shared library needs none of this, and must not
  # fail for want of gmp's or TBB's .pc files: plain flags only.
  list(TRANSFORM sc_pc_core_requires PREPEND -l)
  set(sc_pc_core_libs ${sc_pc_core_requires} ${sc_pc_core_libs})
  set(sc_pc_core_requires)
endif()
list(JOIN sc_pc_core_requires " " SC_PC_CORE_REQUIRES_PRIVATE)
if(SC_PC_CORE_REQUIRES_PRIVATE)
  set(SC_PC_CORE_REQUIRES_PRIVATE
      "Requires.private: ${SC_PC_CORE_REQUIRES_PRIVATE}\n")
endif()
list(JOIN sc_pc_core_libs " " SC_PC_CORE_LIBS_PRIVATE)
set(SC_PC_CLIENT_LIBS_PRIVATE "-lm")
set(SC_PC_PREFIX "@SC_PC_PREFIX@")

set(sc_pc_files)
if(TARGET shortcrust_core)
  list(APPEND sc_pc_files shortcrust)
endif()
if(TARGET shortcrust_client)
  list(APPEND sc_pc_files shortcrust-client)
endif()
foreach(pc ${sc_pc_files})
  configure_file(${CMAKE_CURRENT_LIST_DIR}/${pc}.pc.in
                 ${PROJECT_BINARY_DIR}/package/${pc}.pc.in @ONLY)
  install(CODE "
    set(SC_PC_PREFIX \"\${CMAKE_INSTALL_PREFIX}\")
    configure_file(\"${PROJECT_BINARY_DIR}/package/${pc}.pc.in\"
                   \"${PROJECT_BINARY_DIR}/package/${pc}.pc\" @ONLY)"
    COMPONENT Development)
  install(FILES ${PROJECT_BINARY_DIR}/package/${pc}.pc
          DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig COMPONENT Development)
endforeach()
