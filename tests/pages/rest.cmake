# Golden tests of the long-lag, delayed-oracle, brittleness, noise-sensitivity, Gate 0, identifiers, DualABI-pilot, ladder,
# backbone-variance and audit pages (included by tests/pages/CMakeLists.txt): each runs `actionshift compare` on a committed fixture and the
# page script, and compares with tests/pages/golden/<page>.md (the ladder: one compare per group of
# scripts/ladder_groups.py, pairs from the fixture's ladder*.pairs).
find_package(Python3 COMPONENTS Interpreter)
if(Python3_Interpreter_FOUND)
  foreach(page long_lag brittleness noise_sensitivity gate0 identifiers dualabi_pilot ladder backbone_variance audit delayed_oracle)
    add_test(NAME pages.${page}
             COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/tests/pages/run_page_test.py ${page} $<TARGET_FILE:actionshift>)
    set_tests_properties(pages.${page} PROPERTIES LABELS pages TIMEOUT 120)
  endforeach()
endif()
if(Python3_Interpreter_FOUND)
  # the ladder page's per-contract path, on compare JSONs given a hand-made per_contract field
  add_test(NAME pages.ladder_per_contract
           COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/tests/pages/ladder_per_contract_test.py $<TARGET_FILE:actionshift>)
  set_tests_properties(pages.ladder_per_contract PROPERTIES LABELS pages TIMEOUT 120)
endif()
if(Python3_Interpreter_FOUND)
  # the long-lag page's verdict rule (fixed vs entropy probing, reactive vs delay-aware), every branch on made-up differences
  add_test(NAME pages.long_lag_verdict
           COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/tests/pages/long_lag_verdict_test.py)
  set_tests_properties(pages.long_lag_verdict PROPERTIES LABELS pages TIMEOUT 60)
endif()
if(Python3_Interpreter_FOUND)
  # the delayed-oracle page's rule on "the adapters restore the backbone to its oracle", every branch on made-up differences
  add_test(NAME pages.delayed_oracle_verdict
           COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/tests/pages/delayed_oracle_verdict_test.py)
  set_tests_properties(pages.delayed_oracle_verdict PROPERTIES LABELS pages TIMEOUT 60)
  # the brittleness page's rules for §5.8's Diffusion Policy claims (clean, collapse, restoration to the oracle, probe steps)
  add_test(NAME pages.brittleness_dp_claims
           COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/tests/pages/brittleness_dp_claims_test.py)
  set_tests_properties(pages.brittleness_dp_claims PROPERTIES LABELS pages TIMEOUT 60)
  # the brittleness page's sentence on its own Diffusion Policy jobs: one thread's CPU time against wall time, like with like
  add_test(NAME pages.brittleness_cost_text
           COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/tests/pages/brittleness_cost_text_test.py)
  set_tests_properties(pages.brittleness_cost_text PROPERTIES LABELS pages TIMEOUT 60)
  # the wall-time clause of every page header: jobs an earlier invocation ran are named, not counted as this run's time
  add_test(NAME pages.wall_text COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/tests/pages/wall_text_test.py)
  set_tests_properties(pages.wall_text PROPERTIES LABELS pages TIMEOUT 60)
  # the Diffusion Policy's cost beside the simulator step (the brittleness page): the right benchmark row, one-line refusals
  add_test(NAME pages.dp_cost COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/tests/pages/dp_cost_test.py)
  set_tests_properties(pages.dp_cost PROPERTIES LABELS pages TIMEOUT 60)
endif()
if(TARGET actionshift AND ACTIONSHIFT_BUILD_BENCHMARKS)
  # scripts/brittleness with a tiny Diffusion Policy: its cost step's benchmark files stay out of what compare reads
  add_test(NAME pages.brittleness_dp_script
           COMMAND bash ${PROJECT_SOURCE_DIR}/tests/pages/brittleness_dp_script_test.sh ${CMAKE_BINARY_DIR}
                   ${CMAKE_CURRENT_BINARY_DIR}/brittleness_dp_script)
  set_tests_properties(pages.brittleness_dp_script PROPERTIES LABELS pages TIMEOUT 600)
endif()
if(Python3_Interpreter_FOUND)
  # the audit benchmark's scoring: which committed claims are wrong (new and previous model's JSON), one case per rule
  add_test(NAME pages.audit_scoring COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/tests/pages/audit_scoring_test.py)
  set_tests_properties(pages.audit_scoring PROPERTIES LABELS "pages;audit" TIMEOUT 60)
endif()
