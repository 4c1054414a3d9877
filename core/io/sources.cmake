# Writing bake results to files: OpenImageIO for the formats, OpenColorIO for
# Blender's view transforms. Both through pkg-config: Debian's OCIO has no CMake
# config and OIIO's lists an OpenCV include directory that may not exist.
find_package(PkgConfig REQUIRED)
pkg_check_modules(OIIO REQUIRED IMPORTED_TARGET OpenImageIO)
pkg_check_modules(OCIO REQUIRED IMPORTED_TARGET OpenColorIO)
target_sources(omis_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/image_io.cpp
    ${CMAKE_CURRENT_LIST_DIR}/image_read.cpp
    ${CMAKE_CURRENT_LIST_DIR}/scene_snapshot.cpp)
set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/image_io.cpp PROPERTIES
    COMPILE_DEFINITIONS OMIS_IO_VERSION_STRING="${PROJECT_VERSION}")
target_link_libraries(omis_core PUBLIC PkgConfig::OIIO PkgConfig::OCIO)
