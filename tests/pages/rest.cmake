# Golden tests of the long-lag, brittleness, noise-sensitivity, Gate 0, identifiers and DualABI-pilot
# pages (included by tests/pages/CMakeLists.txt): each runs `actionshift compare` on a committed fixture and the
# page script, and compares with tests/pages/golden/<page>.md. (The ladder page is not yet
# compare-based: its fixture is in tests/pages/data/ladder/, its test to come.)
find_package(Python3 COMPONENTS Interpreter)
if(Python3_Interpreter_FOUND)
  foreach(page long_lag brittleness noise_sensitivity gate0 identifiers dualabi_pilot)
    add_test(NAME pages.${page}
             COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/tests/pages/run_page_test.py ${page} $<TARGET_FILE:actionshift>)
    set_tests_properties(pages.${page} PROPERTIES LABELS pages TIMEOUT 120)
  endforeach()
endif()
