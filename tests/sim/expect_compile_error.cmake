# cmake -DBUILD_DIR=... -DTARGET=... -DEXPECT=<regex> -P expect_compile_error.cmake
# Builds TARGET and passes only if the build fails with output matching EXPECT (a negative-compile test).
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BUILD_DIR} --target ${TARGET}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0)
  message(FATAL_ERROR "${TARGET} compiled, but it must not: ${EXPECT} became reachable")
endif()
if(NOT "${out}${err}" MATCHES "${EXPECT}")
  message(FATAL_ERROR "${TARGET} failed for another reason than the expected one (${EXPECT}):\n${out}${err}")
endif()
message(STATUS "${TARGET} failed to compile, as it must")
