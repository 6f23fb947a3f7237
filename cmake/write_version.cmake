# Writes tools/version.hpp: the version and the commit the build is made from ("unknown" without
# git). Run at configure time and by the palpable_version target at every build, so that a build
# made after a commit names that commit in `palpable --version` and in every run's provenance (at
# configure time only, an incremental build went on naming the commit it was configured at).
# configure_file rewrites the header only when its text changes: a build with nothing new
# recompiles nothing.
# Usage: cmake -DSOURCE_DIR=... -DINPUT=version.hpp.in -DOUTPUT=.../version.hpp
#              -DPROJECT_VERSION=x.y.z [-DGIT_EXECUTABLE=git] -P write_version.cmake
set(PALPABLE_GIT_COMMIT "unknown")
if(GIT_EXECUTABLE)
  execute_process(COMMAND "${GIT_EXECUTABLE}" describe --always --dirty
                  WORKING_DIRECTORY "${SOURCE_DIR}" OUTPUT_VARIABLE _commit
                  OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE _git_rc)
  if(_git_rc EQUAL 0 AND _commit)
    set(PALPABLE_GIT_COMMIT "${_commit}")
  endif()
endif()
configure_file("${INPUT}" "${OUTPUT}" @ONLY)
