target_sources(omis_core PRIVATE
    ${CMAKE_CURRENT_LIST_DIR}/warp.cpp
    ${CMAKE_CURRENT_LIST_DIR}/spherical.cpp
    ${CMAKE_CURRENT_LIST_DIR}/parallel.cpp
    ${CMAKE_CURRENT_LIST_DIR}/shapes.cpp
    ${CMAKE_CURRENT_LIST_DIR}/ellipse.cpp
    ${CMAKE_CURRENT_LIST_DIR}/projected.cpp
    ${CMAKE_CURRENT_LIST_DIR}/irradiance.cpp
    ${CMAKE_CURRENT_LIST_DIR}/sequence.cpp
    ${CMAKE_CURRENT_LIST_DIR}/distribution_2d.cpp
)
