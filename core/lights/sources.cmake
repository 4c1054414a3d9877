target_sources(omis_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/light.cpp
                                 ${CMAKE_CURRENT_LIST_DIR}/light_factories.cpp
                                 ${CMAKE_CURRENT_LIST_DIR}/environment_map.cpp)
