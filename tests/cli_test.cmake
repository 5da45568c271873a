# End-to-end checks of the cmam binary (run by CTest): a render writes the image it names and
# exits 0; a broken scene exits non-zero with a located error and writes nothing.
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
execute_process(COMMAND ${CMAM} render ${SCENES}/demo.pbrt -o ${OUT}/demo.exr --spp 1 --quiet
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS ${OUT}/demo.exr)
  message(FATAL_ERROR "render failed (${rc}): ${err}")
endif()
file(WRITE ${OUT}/bad.pbrt "Camera \"perspective\"\nWorldBegin\nShape \"sphere\" \"float radius\" \"big\"\nWorldEnd\n")
execute_process(COMMAND ${CMAM} render ${OUT}/bad.pbrt -o ${OUT}/bad.png --quiet
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(rc EQUAL 0)
  message(FATAL_ERROR "a broken scene must fail")
endif()
if(NOT err MATCHES "bad.pbrt:3:31: error: float parameter \"radius\" expects a number, got \"big\"")
  message(FATAL_ERROR "unexpected message: ${err}")
endif()
if(EXISTS ${OUT}/bad.png)
  message(FATAL_ERROR "a failed render must not write an image")
endif()
execute_process(COMMAND ${CMAM} --version RESULT_VARIABLE rc OUTPUT_VARIABLE out)
if(NOT rc EQUAL 0 OR NOT out MATCHES "^cmam [0-9]+\\.[0-9]+\\.[0-9]+")
  message(FATAL_ERROR "--version must print the version: ${rc} ${out}")
endif()
# An output folder that does not exist is reported before rendering, and nothing is written.
execute_process(COMMAND ${CMAM} render ${SCENES}/demo.pbrt -o ${OUT}/missing/demo.png --spp 1 --quiet
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "cannot write \"${OUT}/missing/demo.png\": the folder \"${OUT}/missing\" does not exist"
   OR EXISTS ${OUT}/missing)
  message(FATAL_ERROR "a missing output folder must fail before rendering: ${rc} ${err}")
endif()
execute_process(COMMAND ${CMAM} check ${SCENES}/demo.pbrt RESULT_VARIABLE rc OUTPUT_VARIABLE out)
if(NOT rc EQUAL 0 OR NOT out MATCHES "ok:")
  message(FATAL_ERROR "check failed: ${out}")
endif()
# cmam lookup: the JSON object carries the documented keys, and the value of a constant-footprint
# lookup at level 0 is the bilinear texel value.
execute_process(COMMAND ${CMAM} lookup ${SCENES}/textures/brick.png --uv 0.3,0.6 --axes 0.02,0.005,0,0.01 --json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "lookup failed: ${err}")
endif()
foreach(key value levels texels_read ellipse_texels)
  if(NOT out MATCHES "\"${key}\"")
    message(FATAL_ERROR "lookup JSON lacks ${key}: ${out}")
  endif()
endforeach()
# A maximum anisotropy above EWA's limit is used at the limit, with a warning, and the lookup
# reads what it reads at the limit.
execute_process(COMMAND ${CMAM} lookup ${SCENES}/textures/brick.png --uv 0.3,0.6 --axes 0.5,0,0,0.0001 --maxaniso 1000 --json
                RESULT_VARIABLE rc OUTPUT_VARIABLE capped ERROR_VARIABLE err)
execute_process(COMMAND ${CMAM} lookup ${SCENES}/textures/brick.png --uv 0.3,0.6 --axes 0.5,0,0,0.0001 --maxaniso 256 --json
                OUTPUT_VARIABLE at_limit)
if(NOT rc EQUAL 0 OR NOT err MATCHES "warning: --maxaniso 1000 is above cmam's limit of 256" OR NOT capped STREQUAL at_limit)
  message(FATAL_ERROR "--maxaniso above the limit must warn and act as the limit: ${err} ${capped} ${at_limit}")
endif()
execute_process(COMMAND ${CMAM} lookup ${SCENES}/textures/brick.png --uv 0.3,nope RESULT_VARIABLE rc ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "--uv: \"nope\" is not a number")
  message(FATAL_ERROR "bad --uv must fail clearly: ${err}")
endif()
# JSON output is strict JSON (CMake's parser rejects NaN and infinity): a non-finite --uv, given to
# see the fallback, is null, and so is the infinite PSNR of an image against itself.
execute_process(COMMAND ${CMAM} lookup ${SCENES}/textures/brick.png --uv nan,0.6 --axes 0.02,0.005,0,0.01 --json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out)
string(JSON uv0 ERROR_VARIABLE jerr TYPE "${out}" uv 0)
string(JSON fallback ERROR_VARIABLE jerr2 GET "${out}" fallback)
if(NOT rc EQUAL 0 OR NOT uv0 STREQUAL "NULL" OR NOT fallback STREQUAL "ON")
  message(FATAL_ERROR "lookup with a NaN uv must print valid JSON with a null uv and the fallback: ${out} ${jerr} ${jerr2}")
endif()
execute_process(COMMAND ${CMAM} compare ${SCENES}/textures/brick.png ${SCENES}/textures/brick.png --json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out)
string(JSON psnr ERROR_VARIABLE jerr TYPE "${out}" psnr)
string(JSON rmse ERROR_VARIABLE jerr2 GET "${out}" rmse)
if(NOT rc EQUAL 0 OR NOT psnr STREQUAL "NULL" OR NOT rmse EQUAL 0)
  message(FATAL_ERROR "compare of identical images must print valid JSON with a null PSNR: ${out} ${jerr} ${jerr2}")
endif()
