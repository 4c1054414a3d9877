target_sources(omis_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/light.cpp)
