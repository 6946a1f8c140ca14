# fabatlas_add_test(NAME <name> LABELS <label...> SOURCES <src...> LIBS <lib...> [TIMEOUT s])
# Builds a GoogleTest binary into build/bin and registers each TEST with CTest,
# labelled. Tests find the repository, ../shared and build/bin through the
# environment variables FABATLAS_SOURCE_DIR, FABATLAS_SHARED_DIR and
# FABATLAS_BIN_DIR; the same paths are compiled in as FABATLAS_*_DEFAULT for
# running a test binary by hand.
function(fabatlas_add_test)
  cmake_parse_arguments(T "" "NAME;TIMEOUT" "LABELS;SOURCES;LIBS" ${ARGN})
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  add_executable(${T_NAME} ${T_SOURCES})
  target_link_libraries(${T_NAME} PRIVATE ${T_LIBS} GTest::gtest GTest::gtest_main)
  target_include_directories(${T_NAME} PRIVATE ${CMAKE_SOURCE_DIR}/tests/support/include)
  target_compile_definitions(${T_NAME} PRIVATE
    FABATLAS_SOURCE_DIR_DEFAULT="${CMAKE_SOURCE_DIR}"
    FABATLAS_SHARED_DIR_DEFAULT="${FABATLAS_SHARED_DIR}"
    FABATLAS_BIN_DIR_DEFAULT="${CMAKE_BINARY_DIR}/bin")
  # gtest_discover_tests writes PROPERTIES into a script: a list needs its
  # separators escaped twice to survive as one ENVIRONMENT value.
  set(env "FABATLAS_SOURCE_DIR=${CMAKE_SOURCE_DIR}\\\;FABATLAS_SHARED_DIR=${FABATLAS_SHARED_DIR}\\\;FABATLAS_BIN_DIR=${CMAKE_BINARY_DIR}/bin")
  # Test names are "<binary>.<Suite>.<Test>", so `ctest -R design_` selects an area.
  gtest_discover_tests(${T_NAME}
    TEST_PREFIX "${T_NAME}."
    DISCOVERY_TIMEOUT 60
    PROPERTIES
      LABELS "${T_LABELS}"
      TIMEOUT ${T_TIMEOUT}
      ENVIRONMENT "${env}")
endfunction()
