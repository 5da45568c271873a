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

# Runs cmam with the arguments given; sets rc, out and err in the caller.
macro(cmam_run)
  execute_process(COMMAND ${CMAM} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
endmacro()
# Fails unless the last run exited non-zero with `pattern` in its stderr.
macro(expect_failure pattern what)
  if(rc EQUAL 0 OR NOT err MATCHES "${pattern}")
    message(FATAL_ERROR "${what}: exit ${rc}, stderr: ${err}")
  endif()
endmacro()
# A small textured scene (640x400 film) for the checks below; each run takes a few milliseconds.
set(demo ${OUT}/small.pbrt)
file(WRITE ${demo} "LookAt 0 1 -3  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 50\n"
  "Film \"image\" \"integer xresolution\" 640 \"integer yresolution\" 400\nIntegrator \"whitted\"\nWorldBegin\n"
  "LightSource \"distant\" \"point from\" [0 1 -1]\n"
  "Texture \"g\" \"spectrum\" \"imagemap\" \"string filename\" \"${SCENES}/textures/brick.png\"\n"
  "Material \"matte\" \"texture Kd\" \"g\"\n"
  "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" [-5 0 -5 5 0 -5 5 0 5 -5 0 5]"
  " \"point2 uv\" [0 0 8 0 8 8 0 8]\nWorldEnd\n")
# --spp is rounded to a square grid, and says so; a square count says nothing.
cmam_run(render ${demo} -o ${OUT}/spp.exr --spp 5 --resolution 16 --quiet)
if(NOT rc EQUAL 0 OR NOT err MATCHES "cmam: warning: --spp 5 renders 2x2 = 4 samples per pixel")
  message(FATAL_ERROR "--spp 5 must say it renders 4: ${err}")
endif()
cmam_run(render ${demo} -o ${OUT}/spp.exr --spp 4 --resolution 16 --quiet)
if(NOT rc EQUAL 0 OR err MATCHES "warning")
  message(FATAL_ERROR "--spp 4 needs no warning: ${err}")
endif()
# A sampler rendered as stratified does not announce its own count when --spp replaces it.
file(WRITE ${OUT}/halton.pbrt "Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\nSampler \"halton\" \"integer pixelsamples\" 1\nCamera \"perspective\"\nWorldBegin\nShape \"sphere\"\nWorldEnd\n")
cmam_run(render ${OUT}/halton.pbrt -o ${OUT}/halton.exr --spp 4 --quiet)
if(NOT rc EQUAL 0 OR err MATCHES "1x1" OR NOT err MATCHES "halton.pbrt:2:1: warning: Sampler \"halton\" is rendered as \"stratified\" jittered samples, as many as --spp asks for")
  message(FATAL_ERROR "the sampler warning must not name the scene's count under --spp: ${err}")
endif()
cmam_run(render ${OUT}/halton.pbrt -o ${OUT}/halton.exr --quiet)
if(NOT err MATCHES "jittered samples with 1x1 per pixel")
  message(FATAL_ERROR "the sampler warning must name the count rendered: ${err}")
endif()
# --aov footprint: a float image for every footprint source (the CMAM's: the region it built);
# refused, before rendering and writing nothing, for 8-bit formats, point sampling and scenes
# without image textures.
foreach(lod differentials cones cones-aniso cmam)
  file(REMOVE ${OUT}/fp.exr)
  cmam_run(render ${demo} -o ${OUT}/fp.exr --aov footprint --lod ${lod} --resolution 16 --quiet)
  if(NOT rc EQUAL 0 OR NOT EXISTS ${OUT}/fp.exr)
    message(FATAL_ERROR "--aov footprint --lod ${lod} must write the AOV: ${err}")
  endif()
  # Not zeros: the AOV compared with itself prints its mean.
  cmam_run(compare ${OUT}/fp.exr ${OUT}/fp.exr)
  if(NOT rc EQUAL 0 OR NOT out MATCHES "reference mean [0-9.]*[1-9]")
    message(FATAL_ERROR "--aov footprint --lod ${lod} wrote zeros: ${out} ${err}")
  endif()
endforeach()
cmam_run(render ${demo} -o ${OUT}/fp.png --aov footprint --resolution 16 --quiet)
expect_failure("cmam: error: --aov footprint .*need a float image: use .exr or .pfm" "--aov footprint to a PNG")
cmam_run(render ${demo} -o ${OUT}/fp.exr --aov footprint --lod none --resolution 16 --quiet)
expect_failure("cmam: error: --aov footprint: --lod none point-samples" "--aov footprint without a footprint")
cmam_run(render ${OUT}/halton.pbrt -o ${OUT}/fp.pfm --aov footprint --quiet)
expect_failure("this scene has none" "--aov footprint without image textures")
if(EXISTS ${OUT}/fp.png OR EXISTS ${OUT}/fp.pfm)
  message(FATAL_ERROR "a refused AOV must write nothing")
endif()
# Every output format the help lists is written.
foreach(ext exr pfm png jpg tga)
  cmam_run(render ${demo} -o ${OUT}/format.${ext} --spp 1 --resolution 16 --quiet)
  if(NOT rc EQUAL 0 OR NOT EXISTS ${OUT}/format.${ext})
    message(FATAL_ERROR "output format .${ext} must be written: ${err}")
  endif()
endforeach()
# --resolution W keeps the aspect ratio, WxH sets both (with a warning when the aspect changes);
# --crop renders the Film's cropwindow of it.
cmam_run(render ${demo} -o ${OUT}/res.exr --spp 1 --resolution 64)
if(NOT rc EQUAL 0 OR NOT err MATCHES "res.exr: 64x40, " OR err MATCHES "warning")
  message(FATAL_ERROR "--resolution 64 of a 640x400 film must render 64x40: ${err}")
endif()
cmam_run(render ${demo} -o ${OUT}/res.exr --spp 1 --resolution 32x32)
if(NOT rc EQUAL 0 OR NOT err MATCHES "res.exr: 32x32, " OR NOT err MATCHES "warning: --resolution 32x32 has another aspect ratio")
  message(FATAL_ERROR "--resolution 32x32 must render 32x32 and warn: ${err}")
endif()
cmam_run(render ${demo} -o ${OUT}/res.exr --spp 1 --resolution 64 --crop 0.5,1,0.25,0.75)
if(NOT rc EQUAL 0 OR NOT err MATCHES "res.exr: 32x20, ")
  message(FATAL_ERROR "--crop 0.5,1,0.25,0.75 of 64x40 must render 32x20: ${err}")
endif()
cmam_run(render ${demo} -o ${OUT}/res.exr --crop 0.5,0.2,0,1)
expect_failure("cmam: error: --crop: needs X0 < X1 and Y0 < Y1" "an empty --crop")
cmam_run(render ${demo} -o ${OUT}/res.exr --resolution 70000)
expect_failure("cmam: error: --resolution 70000x43750 is above cmam's limits" "a --resolution above the limits")
cmam_run(render ${demo} -o ${OUT}/res.exr --resolution 12y)
expect_failure("cmam: error: --resolution: expected WIDTHxHEIGHT or WIDTH, got \"12y\"" "a bad --resolution")
# Sizes beyond int's range are errors, not wrapped around (4294967328 once rendered 32 wide).
cmam_run(render ${demo} -o ${OUT}/res.exr --resolution 4294967328x24)
expect_failure("cmam: error: --resolution 4294967328x24 is above cmam's limits" "a --resolution beyond int")
cmam_run(eval ${demo} --spp 4294967297 -o ${OUT}/ev)
expect_failure("cmam: error: --spp 4294967297 is above cmam's limit of 1048576" "an eval --spp beyond int")
cmam_run(eval ${demo} --methods ",," -o ${OUT}/ev)
expect_failure("cmam: error: --methods: give at least one method" "an eval without methods")
# eval --resolution and --crop: the ground truth and every method at the film they make (the
# small scene's 640x400 at width 16 is 16x10, its right half 8x10); bad values fail before
# anything is read or written.
cmam_run(eval ${demo} --methods none --spp 1 --reference-spp 1 --resolution 16 --crop 0.5,1,0,1
         --quiet -o ${OUT}/ev_res)
if(NOT rc EQUAL 0 OR NOT EXISTS ${OUT}/ev_res/small/none-spp1.png)
  message(FATAL_ERROR "eval --resolution 16 --crop must evaluate the small scene: ${rc} ${err}")
endif()
# The PNG's IHDR holds the width and the height, 4 bytes each, at bytes 16-23.
file(GLOB images ${OUT}/ev_res/small/*.png)
foreach(png ${images})
  file(READ ${png} head LIMIT 24 HEX)
  if(NOT head MATCHES "000000080000000a$")
    message(FATAL_ERROR "eval --resolution 16 --crop 0.5,1,0,1 must make 8x10 images: ${png} (${head})")
  endif()
endforeach()
cmam_run(eval ${demo} --methods none --resolution 12y -o ${OUT}/ev_bad)
expect_failure("cmam: error: --resolution: expected WIDTHxHEIGHT or WIDTH, got \"12y\"" "a bad eval --resolution")
cmam_run(eval ${demo} --methods none --crop 0.5,0.2,0,1 -o ${OUT}/ev_bad)
expect_failure("cmam: error: --crop: needs X0 < X1 and Y0 < Y1" "an empty eval --crop")
if(EXISTS ${OUT}/ev_bad)
  message(FATAL_ERROR "a bad eval --resolution or --crop must fail before anything is written")
endif()
file(WRITE ${OUT}/a_file "")
cmam_run(eval ${demo} --methods none --spp 1 -o ${OUT}/a_file)
expect_failure("cmam: error: -o ${OUT}/a_file: it is a file, not a folder for the report" "eval -o a file")
# Past the file size limit a write fails with a message and leaves no temporary (SIGXFSZ once
# ended the process and left .res.exr.tmp* behind).
file(MAKE_DIRECTORY ${OUT}/fsz)
execute_process(COMMAND sh -c "ulimit -f 4; exec \"$0\" render \"$1\" -o \"$2\" --resolution 256x160 --spp 1 --quiet"
                        ${CMAM} ${demo} ${OUT}/fsz/big.exr RESULT_VARIABLE rc ERROR_VARIABLE err)
expect_failure("cmam: error: cannot write \"${OUT}/fsz/big.exr\"" "a write past the file size limit")
file(GLOB leftovers ${OUT}/fsz/*)
file(GLOB hidden ${OUT}/fsz/.*)
if(leftovers OR hidden)
  message(FATAL_ERROR "a failed write must leave nothing behind: ${leftovers} ${hidden}")
endif()
# One prefix: located scene errors, "cmam: error:" for everything else (command line included).
cmam_run(render ${demo} --spp 0)
expect_failure("^cmam: error: --spp" "--spp 0")
cmam_run(render ${demo} -o ${OUT}/big.exr --spp 4000000)
expect_failure("^cmam: error: --spp" "--spp above the limit")
cmam_run(check ${SCENES})
expect_failure("scenes: error: cannot read scene file: it is a directory" "check of a folder")
# Bytes a terminal acts on are escaped in messages: an escape sequence or a binary file given as
# a scene never reaches the terminal raw.
string(ASCII 27 esc)
string(ASCII 7 bell)
file(WRITE ${OUT}/garbage.pbrt "${esc}[31m${bell}garbage\n")
cmam_run(check ${OUT}/garbage.pbrt)
expect_failure("garbage.pbrt:1:1: error: unknown directive .x1b " "a binary scene")
if(err MATCHES "${esc}" OR err MATCHES "${bell}")
  message(FATAL_ERROR "raw control bytes in a message: ${err}")
endif()
# cmam eval --help names every footprint source and filter a method may combine; an unknown
# method is refused with the same list.
cmam_run(eval --help)
foreach(name differentials cones-aniso cmam-pixel-hull cmam2d trilinear sat ewa area)
  if(NOT out MATCHES "[ ,]${name}[ ,.]")
    message(FATAL_ERROR "eval --help must list ${name}: ${out}")
  endif()
endforeach()
cmam_run(eval ${demo} --methods cmam+magic -o ${OUT}/eval)
expect_failure("cmam: error: --methods: unknown method \"cmam\+magic\" \(none, or SOURCE\+FILTER with SOURCE one of differentials," "an unknown method")
if(EXISTS ${OUT}/eval)
  message(FATAL_ERROR "an unknown method must fail before anything is written")
endif()
# A render that needs more memory than allowed is refused before rendering, with its sizes; a
# size --max-memory cannot read is an error naming it.
file(WRITE ${OUT}/huge.pbrt "Film \"image\" \"integer xresolution\" 16384 \"integer yresolution\" 16384\nSampler \"stratified\" \"integer xsamples\" 1 \"integer ysamples\" 1\nCamera \"perspective\"\nWorldBegin\nShape \"sphere\"\nWorldEnd\n")
cmam_run(render ${OUT}/huge.pbrt -o ${OUT}/huge.exr --max-memory 1G --quiet)
if(rc EQUAL 0 OR NOT err MATCHES "the render needs about 3.0 GiB more \\(film 3.0 GiB, "
   OR NOT err MATCHES "over the limit of 1.0 GiB set by --max-memory" OR EXISTS ${OUT}/huge.exr)
  message(FATAL_ERROR "a render over --max-memory must be refused before rendering: ${rc} ${err}")
endif()
cmam_run(render ${OUT}/huge.pbrt -o ${OUT}/huge.exr --max-memory lots --quiet)
if(rc EQUAL 0 OR NOT err MATCHES "--max-memory: expected a size such as 8G or 512M, not \"lots\"")
  message(FATAL_ERROR "an unreadable --max-memory must be an error: ${rc} ${err}")
endif()
# A value an option's name table does not know is refused while parsing, before the scene is
# read, with the option, the value and the table's names; --help lists the same names.
cmam_run(render ${OUT}/missing.pbrt --lod foo)
expect_failure("^cmam: error: --lod: unknown \"foo\" [(]expected none, differentials, cones, cones-aniso or cmam[)]" "an unknown --lod")
cmam_run(lookup ${SCENES}/textures/brick.png --uv 0.5,0.5 --wrap foo)
expect_failure("^cmam: error: --wrap: unknown \"foo\" [(]expected repeat, clamp, black or mirror[)]" "an unknown --wrap")
cmam_run(render ${demo} --cmam-adjacency maybe)
expect_failure("^cmam: error: --cmam-adjacency: unknown \"maybe\" [(]expected on or off[)]" "an unknown --cmam-adjacency")
cmam_run(render --help)
if(NOT out MATCHES "--cmam-sat-miss TEXT=average[ \n]+CMAM SAT on a miss: average or paper-literal")
  message(FATAL_ERROR "render --help must list the choices of --cmam-sat-miss: ${out}")
endif()
file(REMOVE_RECURSE ${OUT})
