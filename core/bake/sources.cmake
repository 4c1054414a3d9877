target_sources(omis_core PRIVATE
    ${CMAKE_CURRENT_LIST_DIR}/uv_raster.cpp
    ${CMAKE_CURRENT_LIST_DIR}/bake.cpp
    ${CMAKE_CURRENT_LIST_DIR}/convergence.cpp
    ${CMAKE_CURRENT_LIST_DIR}/dyadic_schedule.cpp
    ${CMAKE_CURRENT_LIST_DIR}/vertex_points.cpp
)
