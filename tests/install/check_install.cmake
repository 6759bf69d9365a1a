# Installs the build tree into WORK_DIR/prefix, then configures, builds and runs, against that
# prefix only, the consumer project (CONSUMER_DIR: the core alone) and the examples
# (EXAMPLES_DIR/query, and EXAMPLES_DIR/render_frame when WITH_RENDER), on the sample data in DATA_DIR.
file(REMOVE_RECURSE ${WORK_DIR})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "install failed (${rc})")
endif()

# Builds the project in `dir` as `name` and runs `program` with the remaining arguments.
function(build_and_run name dir program)
  execute_process(COMMAND ${CMAKE_COMMAND} -S ${dir} -B ${WORK_DIR}/${name} -G ${GENERATOR}
                          -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=Release
                          "-DCMAKE_CXX_FLAGS=${CONSUMER_FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${CONSUMER_FLAGS}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${name}: configuring against the installed package failed (${rc}):\n${out}\n${err}")
  endif()
  execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR}/${name} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${name}: building failed (${rc}):\n${out}\n${err}")
  endif()
  execute_process(COMMAND ${WORK_DIR}/${name}/${program} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${name} printed: ${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${name}: the program failed (${rc})")
  endif()
endfunction()

build_and_run(consumer ${CONSUMER_DIR} kccd_consumer)
build_and_run(example_query ${EXAMPLES_DIR}/query kccd_example_query ${DATA_DIR}/demo_arm.yaml)
if(WITH_RENDER)
  build_and_run(example_render_frame ${EXAMPLES_DIR}/render_frame kccd_example_render_frame
                ${DATA_DIR}/demo_arm.yaml ${DATA_DIR}/demo_camera.yaml ${WORK_DIR}/frame.png)
  if(NOT EXISTS ${WORK_DIR}/frame.png)
    message(FATAL_ERROR "example_render_frame wrote no frame.png")
  endif()
endif()
