# Dependencies that the static ActionShift::eval archive links privately; consumers must find them
# again so the exported link interface resolves (yaml-cpp for experiment files, Threads for the runner).
include(CMakeFindDependencyMacro)
find_dependency(yaml-cpp CONFIG)
find_dependency(Threads)
