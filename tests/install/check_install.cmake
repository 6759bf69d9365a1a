# Installs the build tree into WORK_DIR/prefix, then configures, builds and runs, against that
# prefix only, the consumer project (CONSUMER_DIR: the core alone) and the examples
# (EXAMPLES_DIR/query, EXAMPLES_DIR/render_frame when WITH_RENDER, EXAMPLES_DIR/overlay on a
# recording the installed kccd synthesises when WITH_OVERLAY), on the sample data in DATA_DIR.
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
if(WITH_OVERLAY)
  # A short synthetic recording made by the installed kccd, then overlaid through the library.
  execute_process(COMMAND ${WORK_DIR}/prefix/bin/kccd synth ${DATA_DIR}/demo_arm.yaml -o ${WORK_DIR}/recording
                          --seconds 1 --width 640 --height 360 --appearance volumes -q
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "kccd synth (installed) failed (${rc}): ${err}")
  endif()
  file(MAKE_DIRECTORY ${WORK_DIR}/overlay_out)
  build_and_run(example_overlay ${EXAMPLES_DIR}/overlay kccd_example_overlay ${DATA_DIR}/demo_arm.yaml
                ${WORK_DIR}/recording/camera_true.yaml ${WORK_DIR}/recording/video.mkv ${WORK_DIR}/recording/states.csv
                0.137 ${WORK_DIR}/overlay_out)
  file(READ ${WORK_DIR}/overlay_out/report.json report)
  string(JSON frames GET "${report}" frames_total)
  string(JSON written GET "${report}" frames_written)
  if(NOT frames EQUAL 25 OR NOT written EQUAL 25 OR NOT EXISTS ${WORK_DIR}/overlay_out/overlay.mkv)
    message(FATAL_ERROR "example_overlay: expected 25 frames checked and written, the report says ${frames} and ${written}")
  endif()
endif()
