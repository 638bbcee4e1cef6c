# Runs `stria decode` as a user would: -DSTRIA=<program> -DEMULATOR=<cross emulator or empty> -DOUT=<dir>.
# Inputs come from `stria render` (the simulator's command).
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})

function(run expectedExit)
  execute_process(COMMAND ${EMULATOR} ${STRIA} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL expectedExit)
    message(FATAL_ERROR "stria ${ARGN}\nexited with ${rc}, expected ${expectedExit}:\n${out}${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
  set(err "${err}" PARENT_SCOPE)
endfunction()

run(0 render --scene plane --noise 2 --seed 4 --out ${OUT}/plane.png --calib-out ${OUT}/calib.yaml
    --pattern-out ${OUT}/pattern.yaml)
run(0 render --scene plane --rig endoscope --out ${OUT}/small.png)

# A good frame: all three outputs, statistics with the workspace size.
run(0 decode --calib ${OUT}/calib.yaml --pattern ${OUT}/pattern.yaml --image ${OUT}/plane.png --ply ${OUT}/plane.ply
    --depth ${OUT}/plane.tiff --preview ${OUT}/preview.png --stats --repeat 2)
if(NOT out MATCHES "decoded .*plane.png: ([0-9]+) points")
  message(FATAL_ERROR "unexpected output: ${out}")
endif()
if(CMAKE_MATCH_1 LESS 50000)  # the plane fills the frame: ~54700 edge crossings
  message(FATAL_ERROR "only ${CMAKE_MATCH_1} points on the plane")
endif()
if(NOT out MATCHES "workspace [0-9]+ bytes \\(([0-9]+)\\.[0-9] bytes/pixel for 780x580, (huge|4 KB) pages\\)" OR CMAKE_MATCH_1 GREATER 31)
  message(FATAL_ERROR "no or too large workspace statistics: ${out}")
endif()
file(READ ${OUT}/plane.ply header LIMIT 64)
if(NOT header MATCHES "^ply\nformat binary_little_endian 1.0\n")
  message(FATAL_ERROR "plane.ply is not a binary PLY: ${header}")
endif()
foreach(f plane.tiff preview.png)
  if(NOT EXISTS ${OUT}/${f})
    message(FATAL_ERROR "${f} was not written")
  endif()
endforeach()

# Row pairs (the fast mode): the plane still has a point per camera row and
# edge almost everywhere; with --method dp it is a usage error (exit 2).
run(0 decode --calib ${OUT}/calib.yaml --pattern ${OUT}/pattern.yaml --image ${OUT}/plane.png --ply ${OUT}/pairs.ply
    --row-pairs --stats)
if(NOT out MATCHES "decoded .*plane.png: ([0-9]+) points")
  message(FATAL_ERROR "row pairs: unexpected output: ${out}")
endif()
if(CMAKE_MATCH_1 LESS 50000)
  message(FATAL_ERROR "row pairs: only ${CMAKE_MATCH_1} points on the plane")
endif()
if(NOT out MATCHES "\\(segmented on row pairs\\)")
  message(FATAL_ERROR "row pairs: --stats does not name the mode: ${out}")
endif()
run(2 decode --calib ${OUT}/calib.yaml --pattern ${OUT}/pattern.yaml --image ${OUT}/plane.png --ply ${OUT}/x.ply
    --method dp --row-pairs)
if(NOT err MATCHES "--row-pairs is for --method graph only")
  message(FATAL_ERROR "row pairs with dp: unexpected message: ${err}")
endif()

# A frame of the wrong size: exit 1, both sizes named, no output at all.
run(1 decode --calib ${OUT}/calib.yaml --pattern ${OUT}/pattern.yaml --image ${OUT}/small.png --ply ${OUT}/small.ply
    --depth ${OUT}/small.tiff)
if(NOT err MATCHES "image '.*small.png' is 640x480 but calibration '.*calib.yaml' is for a 780x580 camera")
  message(FATAL_ERROR "wrong size: unexpected message: ${err}")
endif()
file(GLOB leftovers ${OUT}/small.ply* ${OUT}/small.tiff*)
if(leftovers)
  message(FATAL_ERROR "a failed decode left files behind: ${leftovers}")
endif()

# Unreadable image: exit 1 naming the file. Unknown method: usage error, exit 2.
run(1 decode --calib ${OUT}/calib.yaml --pattern ${OUT}/pattern.yaml --image ${OUT}/missing.png --ply ${OUT}/m.ply)
if(NOT err MATCHES "missing.png")
  message(FATAL_ERROR "missing image: unexpected message: ${err}")
endif()
run(2 decode --calib ${OUT}/calib.yaml --pattern ${OUT}/pattern.yaml --image ${OUT}/plane.png --ply ${OUT}/x.ply
    --method magic)
if(NOT err MATCHES "--method 'magic' is not")
  message(FATAL_ERROR "unknown method: unexpected message: ${err}")
endif()

# A raw BGR dump of the wrong length: exit 1 with both byte counts.
file(WRITE ${OUT}/short.raw "not a frame")
run(1 decode --calib ${OUT}/calib.yaml --pattern ${OUT}/pattern.yaml --image ${OUT}/short.raw --ply ${OUT}/r.ply
    --raw-format bgr8 --raw-size 780x580)
if(NOT err MATCHES "has 11 bytes but bgr8 780x580 needs 1357200")
  message(FATAL_ERROR "short raw frame: unexpected message: ${err}")
endif()
