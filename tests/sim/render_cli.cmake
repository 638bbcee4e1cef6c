# Runs `stria render` as a user would: -DSTRIA=<program> -DEMULATOR=<cross emulator or empty> -DOUT=<dir>.
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})

execute_process(COMMAND ${EMULATOR} ${STRIA} render --scene sphere --seed 3 --noise 2 --out ${OUT}/sphere.png
                        --depth ${OUT}/depth.tiff --columns ${OUT}/columns.tiff --calib-out ${OUT}/calib.yaml
                        --pattern-out ${OUT}/pattern.yaml
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "stria render exited with ${rc}: ${err}")
endif()
if(NOT out MATCHES "wrote .*sphere.png: scene sphere, rig desktop \\(780x580\\)")
  message(FATAL_ERROR "unexpected output: ${out}")
endif()
# PNG signature, then the IHDR chunk: width 780 (0x30c), height 580 (0x244).
file(READ ${OUT}/sphere.png header HEX LIMIT 24)
if(NOT header STREQUAL "89504e470d0a1a0a0000000d494844520000030c00000244")
  message(FATAL_ERROR "sphere.png is not a 780x580 PNG: ${header}")
endif()
foreach(tiff depth columns)
  file(SIZE ${OUT}/${tiff}.tiff size)
  if(size LESS 1809600)  # 780 x 580 floats
    message(FATAL_ERROR "${tiff}.tiff has only ${size} bytes")
  endif()
endforeach()
file(STRINGS ${OUT}/calib.yaml width REGEX "^camera_width: 780$")
file(STRINGS ${OUT}/pattern.yaml stripes REGEX "^stripes: 128$")
if(NOT width OR NOT stripes)
  message(FATAL_ERROR "calib.yaml or pattern.yaml does not describe the desktop rig")
endif()

# Unknown scene: exit 2, the known scenes listed, nothing written.
execute_process(COMMAND ${EMULATOR} ${STRIA} render --scene teapot --out ${OUT}/teapot.png
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 2)
  message(FATAL_ERROR "unknown scene: exit ${rc}, expected 2")
endif()
if(NOT err MATCHES "unknown scene 'teapot': known scenes are plane, sphere, relief, clutter, fan, fingertip, tube")
  message(FATAL_ERROR "unknown scene: unexpected message: ${err}")
endif()
if(EXISTS ${OUT}/teapot.png)
  message(FATAL_ERROR "teapot.png was written despite the error")
endif()

# Unwritable output: exit 1, no partial set of files.
execute_process(COMMAND ${EMULATOR} ${STRIA} render --scene plane --out ${OUT}/plane.png
                        --depth ${OUT}/no-such-dir/depth.tiff
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR EXISTS ${OUT}/plane.png)
  message(FATAL_ERROR "unwritable depth file: exit ${rc} (expected 1), plane.png left behind: ${err}")
endif()
