# Dependencies of the static ActionShift::sim archive (linked PRIVATE, still needed at link time).
include(CMakeFindDependencyMacro)
find_dependency(PkgConfig)
if(NOT TARGET PkgConfig::BULLET)
  pkg_check_modules(BULLET REQUIRED IMPORTED_TARGET bullet-float64)
endif()
find_dependency(urdfdom CONFIG)
find_dependency(assimp 5.2 CONFIG)
find_dependency(Threads)
