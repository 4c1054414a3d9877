# Embree geometry the direct-lighting engine traces shadow rays against.
find_package(embree 3 CONFIG REQUIRED)
target_sources(omis_core PRIVATE
    ${CMAKE_CURRENT_LIST_DIR}/device.cpp
    ${CMAKE_CURRENT_LIST_DIR}/geometry_scene.cpp
    ${CMAKE_CURRENT_LIST_DIR}/emitter_shapes.cpp
    ${CMAKE_CURRENT_LIST_DIR}/surface_contacts.cpp
)
target_link_libraries(omis_core PUBLIC embree)
