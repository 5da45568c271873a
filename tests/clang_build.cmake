# Builds the filtering library, its tests and the example tracer with another compiler (Clang
# when the project is built with GCC), warnings as errors, and runs the library's tests: the
# library is meant to be compiled into other people's tracers, with their compiler.
file(REMOVE_RECURSE ${WORK})
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SRC} -B ${WORK} -G Ninja -DCMAKE_BUILD_TYPE=Release
                        -DCMAKE_CXX_COMPILER=${CXX} -DCMAM_BUILD_RENDERER=OFF
                        -DCMAM_BUILD_BENCHMARKS=OFF -DCMAM_BUILD_EXAMPLES=ON -DCMAM_BUILD_TESTS=ON
                        -DCMAKE_CXX_FLAGS=-Werror
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configure with ${CXX} failed: ${out} ${err}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "build with ${CXX} failed: ${out} ${err}")
endif()
execute_process(COMMAND ${WORK}/tests/texture_test --gtest_brief=1 RESULT_VARIABLE rc
                OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "texture_test built with ${CXX} failed: ${out} ${err}")
endif()
execute_process(COMMAND ${WORK}/examples/tiny_tracer ${WORK}/tiny_tracer RESULT_VARIABLE rc
                OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "tiny_tracer built with ${CXX} failed: ${out} ${err}")
endif()
