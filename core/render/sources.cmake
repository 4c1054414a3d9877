find_package(TBB REQUIRED)
target_sources(omis_core PRIVATE
    ${CMAKE_CURRENT_LIST_DIR}/scene.cpp
    ${CMAKE_CURRENT_LIST_DIR}/techniques.cpp
    ${CMAKE_CURRENT_LIST_DIR}/effect_plan.cpp
    ${CMAKE_CURRENT_LIST_DIR}/direct_lighting.cpp
    ${CMAKE_CURRENT_LIST_DIR}/lighting_context.cpp
    ${CMAKE_CURRENT_LIST_DIR}/point_lighting.cpp
    ${CMAKE_CURRENT_LIST_DIR}/point_setup.cpp
    ${CMAKE_CURRENT_LIST_DIR}/technique_draws.cpp
    ${CMAKE_CURRENT_LIST_DIR}/point_sample.cpp
    ${CMAKE_CURRENT_LIST_DIR}/integrand.cpp
    ${CMAKE_CURRENT_LIST_DIR}/light_tables.cpp
    ${CMAKE_CURRENT_LIST_DIR}/light_densities.cpp
    ${CMAKE_CURRENT_LIST_DIR}/shape_draws.cpp
    ${CMAKE_CURRENT_LIST_DIR}/lights_along.cpp
    ${CMAKE_CURRENT_LIST_DIR}/point_estimate.cpp
    ${CMAKE_CURRENT_LIST_DIR}/receiver.cpp
    ${CMAKE_CURRENT_LIST_DIR}/light_selection.cpp
    ${CMAKE_CURRENT_LIST_DIR}/light_tree_walk.cpp
    ${CMAKE_CURRENT_LIST_DIR}/texel_tables.cpp
)
target_link_libraries(omis_core PUBLIC TBB::tbb)
