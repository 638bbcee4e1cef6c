# `stria decode --method dp` as a user would run it on a rendered plane:
# -DSTRIA=<program> -DEMULATOR=<cross emulator or empty> -DOUT=<dir>.
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
execute_process(COMMAND ${EMULATOR} ${STRIA} render --scene plane --noise 2 --out ${OUT}/plane.png
                        --calib-out ${OUT}/calib.yaml --pattern-out ${OUT}/pattern.yaml
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "stria render exited with ${rc}: ${err}")
endif()

# The plane shows 54661 edge crossings; the baseline finds nearly all of them
# (and some spurious ones at noise 2).
execute_process(COMMAND ${EMULATOR} ${STRIA} decode --method dp --calib ${OUT}/calib.yaml
                        --pattern ${OUT}/pattern.yaml --image ${OUT}/plane.png --ply ${OUT}/dp.ply
                        --depth ${OUT}/dp.tiff --stats
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "stria decode --method dp exited with ${rc}: ${err}")
endif()
if(NOT out MATCHES "decoded [^\n]*plane.png: ([0-9]+) points")
  message(FATAL_ERROR "unexpected output: ${out}")
endif()
if(CMAKE_MATCH_1 LESS 54000 OR CMAKE_MATCH_1 GREATER 60000)
  message(FATAL_ERROR "the DP baseline decoded ${CMAKE_MATCH_1} points, expected 54000..60000")
endif()
if(NOT out MATCHES "DP baseline: points [0-9]+, total [0-9.]+ ms")
  message(FATAL_ERROR "--stats did not print the baseline's line: ${out}")
endif()
file(SIZE ${OUT}/dp.tiff size)
if(size LESS 1809600)  # 780 x 580 floats
  message(FATAL_ERROR "dp.tiff has only ${size} bytes")
endif()

# An unknown method is a usage error that names the choices; nothing written.
execute_process(COMMAND ${EMULATOR} ${STRIA} decode --method magic --calib ${OUT}/calib.yaml
                        --pattern ${OUT}/pattern.yaml --image ${OUT}/plane.png --ply ${OUT}/magic.ply
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "--method 'magic' is not one of graph, dp" OR EXISTS ${OUT}/magic.ply)
  message(FATAL_ERROR "unknown method: exit ${rc} (expected 2), message: ${err}")
endif()
