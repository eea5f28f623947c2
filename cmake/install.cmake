# `make install PREFIX=DIR` (cmake --install): the tool, the header, the static and the
# shared library, a pkg-config file, a CMake package (the imported target
# meshcsg::meshcsg), the manual page and the Python package, in Debian's layout
# (libraries in DIR/lib, Python in DIR/lib/python3/dist-packages).
# The list of installed files goes to DIR/share/meshcsg/installed-files, which
# `make uninstall` reads.
include(CMakePackageConfigHelpers)
set(MCSG_INSTALL_CMAKEDIR lib/cmake/meshcsg)

install(TARGETS meshcsg_cli RUNTIME DESTINATION bin)
install(FILES ${CMAKE_SOURCE_DIR}/include/meshcsg.h DESTINATION include)
install(FILES ${CMAKE_SOURCE_DIR}/docs/meshcsg.1 DESTINATION share/man/man1)
# The Python package (on the shared library, found relative to it), in Debian's layout.
if(MCSG_SHARED)
  install(DIRECTORY ${CMAKE_SOURCE_DIR}/python/meshcsg DESTINATION lib/python3/dist-packages
          FILES_MATCHING PATTERN "*.py" PATTERN "__pycache__" EXCLUDE)
endif()

# meshcsg::meshcsg is the shared library; meshcsg::meshcsg_static the static one (which
# needs GMP and the threads library at link time, as its interface says).
set(MCSG_INSTALLED_LIBRARIES meshcsg)
if(MCSG_SHARED)
  set_target_properties(meshcsg PROPERTIES EXPORT_NAME meshcsg_static)
  list(APPEND MCSG_INSTALLED_LIBRARIES meshcsg_shared)
endif()
install(TARGETS ${MCSG_INSTALLED_LIBRARIES} EXPORT meshcsgTargets
        ARCHIVE DESTINATION lib LIBRARY DESTINATION lib)
install(EXPORT meshcsgTargets NAMESPACE meshcsg:: DESTINATION ${MCSG_INSTALL_CMAKEDIR})
configure_file(${CMAKE_SOURCE_DIR}/cmake/meshcsgConfig.cmake.in
               ${CMAKE_BINARY_DIR}/meshcsgConfig.cmake @ONLY)
write_basic_package_version_file(${CMAKE_BINARY_DIR}/meshcsgConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMajorVersion)
install(FILES ${CMAKE_BINARY_DIR}/meshcsgConfig.cmake
              ${CMAKE_BINARY_DIR}/meshcsgConfigVersion.cmake
        DESTINATION ${MCSG_INSTALL_CMAKEDIR})

configure_file(${CMAKE_SOURCE_DIR}/cmake/meshcsg.pc.in ${CMAKE_BINARY_DIR}/meshcsg.pc @ONLY)
install(FILES ${CMAKE_BINARY_DIR}/meshcsg.pc DESTINATION lib/pkgconfig)

# Last: every file above is in CMAKE_INSTALL_MANIFEST_FILES by now.
install(CODE [[
  set(root "$ENV{DESTDIR}${CMAKE_INSTALL_PREFIX}")
  set(list "${root}/share/meshcsg/installed-files")
  set(lines "share/meshcsg/installed-files\n")
  foreach(file IN LISTS CMAKE_INSTALL_MANIFEST_FILES)
    foreach(base "${root}/" "${CMAKE_INSTALL_PREFIX}/")
      string(LENGTH "${base}" length)
      string(SUBSTRING "${file}" 0 ${length} head)
      if(head STREQUAL base)
        string(SUBSTRING "${file}" ${length} -1 file)
        break()
      endif()
    endforeach()
    string(APPEND lines "${file}\n")
  endforeach()
  file(WRITE "${list}" "${lines}")
  message(STATUS "Installing: ${list}")
]])
