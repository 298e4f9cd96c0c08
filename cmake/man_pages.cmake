# Man pages from a program's own --help, at build time (cmake -P; cmake/Install.cmake runs it).
#   -DHELP2MAN=path -DPROGRAM=path -DNAME=hmc -DVERSION=0.1.0 -DSUMMARY="..." -DOUT_DIR=dir
#   [-DSUBCOMMANDS=ON] [-DSEE_ALSO="hmc-sim;hmc-uf2"] [-DSTAMP=file]
# Writes OUT_DIR/NAME.1.gz. With SUBCOMMANDS, also NAME-SUB.1.gz for each subcommand that
# `NAME --help` lists under "Subcommands:" (CLI11's layout), from `NAME SUB --help`, and NAME.1's
# SEE ALSO names them, except where a program in SEE_ALSO has that name. Pages are compressed with gzip -9n, as Debian installs them.
cmake_minimum_required(VERSION 3.25)
foreach(required HELP2MAN PROGRAM NAME VERSION SUMMARY OUT_DIR)
  if(NOT DEFINED ${required})
    message(FATAL_ERROR "man_pages.cmake: -D${required}=... is required")
  endif()
endforeach()
find_program(GZIP gzip REQUIRED)
file(MAKE_DIRECTORY ${OUT_DIR})

# page(name summary help_option see_also...): one page, NAME-like title from --version-string.
function(page name summary help_option)
  set(include_file ${OUT_DIR}/${name}.h2m)
  set(see_also "")
  foreach(other ${ARGN})
    string(APPEND see_also ".BR ${other} (1)\n")
  endforeach()
  if(see_also)
    file(WRITE ${include_file} "[SEE ALSO]\n${see_also}")
  else()
    file(WRITE ${include_file} "")
  endif()
  execute_process(COMMAND ${HELP2MAN} --no-info --no-discard-stderr "--version-string=${name} ${VERSION}"
                          "--help-option=${help_option}" "--name=${summary}" "--include=${include_file}"
                          --output=${OUT_DIR}/${name}.1 ${PROGRAM}
                  RESULT_VARIABLE failed ERROR_VARIABLE errors)
  if(failed)
    message(FATAL_ERROR "help2man could not write ${name}(1) from `${PROGRAM} ${help_option}`: ${errors}")
  endif()
  file(REMOVE ${include_file})
  execute_process(COMMAND ${GZIP} -9nf ${OUT_DIR}/${name}.1 RESULT_VARIABLE failed)
  if(failed)
    message(FATAL_ERROR "gzip failed on ${OUT_DIR}/${name}.1")
  endif()
endfunction()

set(pages "")
if(SUBCOMMANDS)
  execute_process(COMMAND ${PROGRAM} --help OUTPUT_VARIABLE help RESULT_VARIABLE failed)
  if(failed)
    message(FATAL_ERROR "`${PROGRAM} --help` failed")
  endif()
  string(REPLACE ";" "<semicolon>" help "${help}")  # a list's separator; restored in each summary
  string(REPLACE "\n" ";" lines "${help}")
  set(in_list FALSE)
  foreach(line IN LISTS lines)
    if(line STREQUAL "Subcommands:")
      set(in_list TRUE)
    elseif(in_list AND line MATCHES "^  ([a-z][a-z0-9-]*)  +(.*)$")
      set(sub ${CMAKE_MATCH_1})
      string(STRIP "${CMAKE_MATCH_2}" sub_summary)
      string(REPLACE "<semicolon>" ";" sub_summary "${sub_summary}")
      # A program of that name has its own page (`hmc sim` and hmc-sim): it keeps the name.
      if(NOT "${NAME}-${sub}" IN_LIST SEE_ALSO)
        page(${NAME}-${sub} "${sub_summary}" "${sub} --help" ${NAME})
        list(APPEND pages ${NAME}-${sub})
      endif()
    elseif(in_list AND NOT line MATCHES "^  ")
      set(in_list FALSE)
    endif()
  endforeach()
  if(NOT pages)
    message(FATAL_ERROR "`${PROGRAM} --help` lists no subcommands under \"Subcommands:\"")
  endif()
endif()
page(${NAME} "${SUMMARY}" --help ${pages} ${SEE_ALSO})
if(DEFINED STAMP)
  file(TOUCH ${STAMP})
endif()
