# Installs the build into a fresh prefix, then configures, builds and runs tests/install/example
# against it with find_package(palpable): the library others embed works as installed.
# Usage: cmake -DBUILD=<build dir> -DSOURCE=<example dir> -DWORK=<scratch dir>
#              [-DCXX=<compiler>] [-DGENERATOR=<generator>] [-DPYTHON=<python> -DSCENE=<scene>]
#              -P check.cmake
# With PYTHON, the installed Python package is imported from the moved prefix and runs SCENE.
# The prefix is moved after installing, so the package must be relocatable (no absolute paths to
# the build or the first prefix). The test's verdict is this script's exit status.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --prefix ${WORK}/staged
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install failed (${rc}):\n${err}")
endif()
file(RENAME ${WORK}/staged ${WORK}/prefix)
set(expected include/palpable/scheduler/simulation.hpp include/palpable/core/shape.hpp
             lib/cmake/palpable/palpableConfig.cmake lib/cmake/palpable/palpableConfigVersion.cmake
             lib/cmake/palpable/palpableTargets.cmake)
foreach(module core distance impulse scheduler scenarios)
  list(APPEND expected lib/libpalpable_${module}.a)
endforeach()
foreach(f IN LISTS expected)
  if(NOT EXISTS ${WORK}/prefix/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
# A module's private headers (*_detail.hpp, *_impl.hpp) stay behind.
file(GLOB_RECURSE private_headers RELATIVE ${WORK}/prefix ${WORK}/prefix/include/*_detail.hpp
     ${WORK}/prefix/include/*_impl.hpp)
if(private_headers)
  message(FATAL_ERROR "private headers installed: ${private_headers}")
endif()
# Only the five simulator modules: no cross-check (libccd) or tool library, no tests.
file(GLOB installed_libs RELATIVE ${WORK}/prefix/lib ${WORK}/prefix/lib/*.a)
list(LENGTH installed_libs n)
if(NOT n EQUAL 5)
  message(FATAL_ERROR "expected the five module libraries, installed: ${installed_libs}")
endif()

set(configure_args -S ${SOURCE} -B ${WORK}/build -DCMAKE_BUILD_TYPE=Release
                   -DCMAKE_PREFIX_PATH=${WORK}/prefix)
if(GENERATOR)
  list(APPEND configure_args -G ${GENERATOR})
endif()
if(CXX)
  list(APPEND configure_args -DCMAKE_CXX_COMPILER=${CXX})
endif()
execute_process(COMMAND ${CMAKE_COMMAND} ${configure_args}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring the example failed:\n${out}\n${err}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK}/build RESULT_VARIABLE rc
                OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the example failed:\n${out}\n${err}")
endif()
execute_process(COMMAND ${WORK}/build/falling_ball RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
message(STATUS "${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the example failed (${rc}): its first impact is not at sqrt(2 h / g)\n${err}")
endif()
if(NOT out MATCHES "^first impact at 0\\.451523640[0-9]* s")
  message(FATAL_ERROR "unexpected output from the example: ${out}")
endif()

if(PYTHON)
  execute_process(COMMAND ${CMAKE_COMMAND} -E env
                          PYTHONPATH=${WORK}/prefix/lib/python3/dist-packages ${PYTHON} -c
                          "import palpable, sys; r = palpable.run(sys.argv[1], end=0.1); print(palpable.__file__, len(r.t))"
                          ${SCENE}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0 OR NOT out MATCHES "^${WORK}/prefix/lib/python3/dist-packages/palpable/__init__.py ")
    message(FATAL_ERROR "the installed Python package did not run from the prefix (${rc}):\n${out}\n${err}")
  endif()
  message(STATUS "installed Python package: ${out}")
endif()
