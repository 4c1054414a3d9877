target_sources(omis_core PRIVATE
    ${CMAKE_CURRENT_LIST_DIR}/estimator.cpp
    ${CMAKE_CURRENT_LIST_DIR}/solver.cpp
    ${CMAKE_CURRENT_LIST_DIR}/allocation.cpp
)
