# fabatlas_add_test(NAME <name> LABELS <label...> SOURCES <src...> LIBS <lib...>)
# Builds a GoogleTest binary into build/bin and registers each TEST with CTest,
# labelled. Tests find the repository and ../shared through the environment
# variables FABATLAS_SOURCE_DIR and FABATLAS_SHARED_DIR.
function(fabatlas_add_test)
  cmake_parse_arguments(T "" "NAME;TIMEOUT" "LABELS;SOURCES;LIBS" ${ARGN})
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  add_executable(${T_NAME} ${T_SOURCES})
  target_link_libraries(${T_NAME} PRIVATE ${T_LIBS} GTest::gtest GTest::gtest_main)
  gtest_discover_tests(${T_NAME}
    DISCOVERY_TIMEOUT 60
    PROPERTIES
      LABELS "${T_LABELS}"
      TIMEOUT ${T_TIMEOUT}
      ENVIRONMENT "FABATLAS_SOURCE_DIR=${CMAKE_SOURCE_DIR};FABATLAS_SHARED_DIR=${FABATLAS_SHARED_DIR};FABATLAS_BIN_DIR=${CMAKE_BINARY_DIR}/bin")
endfunction()
