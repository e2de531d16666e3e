# Dependencies of the static ActionShift::render archive (linked PRIVATE, still needed at link time).
# OSMesa is not among them: the renderer opens libOSMesa.so.8 with dlopen(3) when it first renders.
include(CMakeFindDependencyMacro)
find_dependency(PkgConfig)
if(NOT TARGET PkgConfig::BULLET)
  pkg_check_modules(BULLET REQUIRED IMPORTED_TARGET bullet-float64)
endif()
find_dependency(PNG)
find_dependency(GIF)
