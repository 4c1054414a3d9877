target_sources(omis_core PRIVATE
    ${CMAKE_CURRENT_LIST_DIR}/uv_raster.cpp
    ${CMAKE_CURRENT_LIST_DIR}/bake.cpp
    ${CMAKE_CURRENT_LIST_DIR}/bake_allocation.cpp
    ${CMAKE_CURRENT_LIST_DIR}/bake_layout.cpp
    ${CMAKE_CURRENT_LIST_DIR}/bake_means.cpp
    ${CMAKE_CURRENT_LIST_DIR}/bake_outputs.cpp
    ${CMAKE_CURRENT_LIST_DIR}/bake_points.cpp
    ${CMAKE_CURRENT_LIST_DIR}/bake_schedule.cpp
    ${CMAKE_CURRENT_LIST_DIR}/convergence.cpp
    ${CMAKE_CURRENT_LIST_DIR}/dyadic_schedule.cpp
    ${CMAKE_CURRENT_LIST_DIR}/vertex_points.cpp
)
