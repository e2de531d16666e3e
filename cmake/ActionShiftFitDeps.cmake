# Dependencies that the static ActionShift::fit archive links privately; consumers must find them
# again so the exported link interface resolves (Ceres for the scale corrector's least-squares fit).
include(CMakeFindDependencyMacro)
find_dependency(Ceres)
