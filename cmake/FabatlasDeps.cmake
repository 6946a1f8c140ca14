# All third-party packages, found once. Order matters (known CMake
# pitfalls): TBB before Ceres and OpenVDB; OpenMesh through its CONFIG file
# because CGAL ships a FindOpenMesh of its own.
find_package(Threads REQUIRED)
find_package(TBB CONFIG REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(Ceres REQUIRED)
list(APPEND CMAKE_MODULE_PATH /usr/lib/x86_64-linux-gnu/cmake/OpenVDB)
find_package(OpenVDB REQUIRED)
find_package(CGAL REQUIRED)
find_package(OpenMesh CONFIG REQUIRED)
find_package(embree 3 REQUIRED)
find_package(fcl CONFIG REQUIRED)  # continuous collision (swept/continuous_contact.h)
find_package(yaml-cpp REQUIRED)
find_package(nlohmann_json REQUIRED)
find_package(CLI11 CONFIG REQUIRED)
find_package(spdlog CONFIG REQUIRED)
find_package(PNG REQUIRED)
find_package(OpenSSL REQUIRED)
# The cluster (issue 4): gRPC + protobuf, SQLite for the durable job store.
find_package(Protobuf REQUIRED)
find_package(gRPC CONFIG REQUIRED)
find_package(SQLite3 REQUIRED)
# The artifact (issue 5): cache entries as glTF binary.
find_package(TinyGLTF CONFIG REQUIRED)
find_package(PkgConfig REQUIRED)
pkg_check_modules(MUPARSER REQUIRED IMPORTED_TARGET muparser)
# Clipper 6.4.2: the 2-D booleans, offsets and minkowski OpenSCAD 2021.01 uses
# (scad/evaluate_2d.h).
pkg_check_modules(POLYCLIPPING REQUIRED IMPORTED_TARGET polyclipping)
if(FABATLAS_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(FABATLAS_BUILD_BENCH)
  find_package(benchmark REQUIRED)
endif()

# fabatlas_load_first(<program>): OpenVDB and FCL first among the shared
# libraries <program> names (DT_NEEDED), so that they come right after it in
# the loader's global search scope. Neither library is linked with
# -Bsymbolic, so each of their relocations against their own symbols
# (~55,000 and ~12,000, OpenVDB's names ~300 characters long) is looked up
# through that scope from its start; at their place as dependencies of
# dependencies (65th and 67th of the 112 objects of fabatlas-worker) those
# lookups were most of the CPU of every process start (docs/benchmarks.md,
# Scale). --no-as-needed: on the link line they come before the objects that
# use them.
function(fabatlas_load_first program)
  target_link_options(${program} PRIVATE "LINKER:--push-state,--no-as-needed"
    "$<TARGET_FILE:OpenVDB::openvdb>" "$<TARGET_FILE:fcl>" "LINKER:--pop-state")
endfunction()
