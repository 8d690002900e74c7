# Installs the build into a fresh prefix, then configures, builds and runs tests/consumer against it.
file(REMOVE_RECURSE ${WORK_DIR})
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  message(STATUS "${out}")
  set(last_output "${out}" PARENT_SCOPE)
endfunction()
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} -S ${CONSUMER_SOURCE} -B ${WORK_DIR}/build -G ${GENERATOR} -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix
    -DCMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${WORK_DIR}/build/consumer)

# The installed programs run from the prefix, and from wherever the prefix is moved (relative run
# paths: no LD_LIBRARY_PATH, no ldconfig).
if(EXISTS ${WORK_DIR}/prefix/bin/voxfuse)
  file(RENAME ${WORK_DIR}/prefix ${WORK_DIR}/moved_prefix)
  run(${CMAKE_COMMAND} -E env --unset=LD_LIBRARY_PATH ${WORK_DIR}/moved_prefix/bin/voxfuse --help)
  run(${CMAKE_COMMAND} -E env --unset=LD_LIBRARY_PATH ${WORK_DIR}/moved_prefix/bin/voxfuse ${DATA_DIR} --frames 3 --render-every 0
      --out ${WORK_DIR}/run)
  if(NOT EXISTS ${WORK_DIR}/run/summary.json)
    message(FATAL_ERROR "the installed voxfuse wrote no summary.json")
  endif()
  # With no SOURCE it runs on the room installed beside it, not on the source tree's.
  run(${CMAKE_COMMAND} -E env --unset=LD_LIBRARY_PATH ${WORK_DIR}/moved_prefix/bin/voxfuse --frames 2 --render-every 0
      --out ${WORK_DIR}/run_default)
  file(READ ${WORK_DIR}/run_default/summary.json summary)
  string(JSON source GET "${summary}" source)
  if(NOT source MATCHES "${WORK_DIR}/moved_prefix/share/voxfuse/synthetic_room")
    message(FATAL_ERROR "the installed voxfuse with no SOURCE read ${source}")
  endif()
  run(${CMAKE_COMMAND} -E env --unset=LD_LIBRARY_PATH ${WORK_DIR}/moved_prefix/bin/voxfuse --version)
  if(NOT last_output MATCHES "^voxfuse [0-9]+\\.[0-9]+\\.[0-9]+")
    message(FATAL_ERROR "voxfuse --version printed: ${last_output}")
  endif()
  foreach(program voxfuse_bench voxfuse_synth)
    if(NOT EXISTS ${WORK_DIR}/moved_prefix/bin/${program})
      message(FATAL_ERROR "${program} was not installed")
    endif()
  endforeach()
endif()

# The Python package installed with them imports from the moved prefix. (No ';' in the code: run()
# passes its arguments as a CMake list.)
if(PYTHON AND EXISTS ${WORK_DIR}/moved_prefix/lib/python3/dist-packages/voxfuse)
  run(${CMAKE_COMMAND} -E env --unset=LD_LIBRARY_PATH PYTHONPATH=${WORK_DIR}/moved_prefix/lib/python3/dist-packages
      ${PYTHON} -c "import voxfuse\nassert voxfuse.Settings().voxel == 's_rgb'\nprint('installed voxfuse:', voxfuse.__file__)")
  if(NOT last_output MATCHES "installed voxfuse: ${WORK_DIR}/moved_prefix/")
    message(FATAL_ERROR "the installed Python package was not the one imported: ${last_output}")
  endif()
endif()
