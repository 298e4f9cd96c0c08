# Size report and budget check for a firmware image, run by the build (cmake -P). Prints the
# per-section sizes and the totals, writes them to REPORT, and fails the build when the image
# is over budget.
#   flash = text + data   (code, constants, vector table, constructor tables, .data's initial values)
#   RAM   = data + bss    (.bss includes the NOLOAD stack reserve, samd21_sections.ld)
# Inputs: SIZE_TOOL (arm-none-eabi-size), ELF, REPORT, FLASH_BUDGET, RAM_BUDGET (bytes).
foreach(var SIZE_TOOL ELF REPORT FLASH_BUDGET RAM_BUDGET)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "size_check.cmake: ${var} is not set")
  endif()
endforeach()

execute_process(COMMAND ${SIZE_TOOL} -B -d ${ELF} OUTPUT_VARIABLE berkeley RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "size_check.cmake: ${SIZE_TOOL} failed on ${ELF}")
endif()
execute_process(COMMAND ${SIZE_TOOL} -A -d ${ELF} OUTPUT_VARIABLE sections)

string(REGEX MATCH "\n *([0-9]+)[ \t]+([0-9]+)[ \t]+([0-9]+)" totals "${berkeley}")
if(NOT totals)
  message(FATAL_ERROR "size_check.cmake: cannot read the totals of\n${berkeley}")
endif()
set(text ${CMAKE_MATCH_1})
set(data ${CMAKE_MATCH_2})
set(bss ${CMAKE_MATCH_3})
# `size -B` sorts sections by their flags: .data, which holds the step interrupt's code copied
# to RAM (.ramfunc, samd21_sections.ld), counts as text there. Take .data from `size -A`.
string(REGEX MATCH "\n[.]data[ \t]+([0-9]+)" data_row "${sections}")
if(data_row AND NOT data EQUAL CMAKE_MATCH_1)
  math(EXPR text "${text} - ${CMAKE_MATCH_1} + ${data}")
  set(data ${CMAKE_MATCH_1})
endif()
math(EXPR flash "${text} + ${data}")
math(EXPR ram "${data} + ${bss}")
math(EXPR flash_pct "100 * ${flash} / ${FLASH_BUDGET}")
math(EXPR ram_pct "100 * ${ram} / ${RAM_BUDGET}")

get_filename_component(name ${ELF} NAME)
set(summary "${name}: flash ${flash} of ${FLASH_BUDGET} bytes (${flash_pct} %), RAM ${ram} of ${RAM_BUDGET} bytes (${ram_pct} %) [text ${text}, data ${data}, bss+stack ${bss}]")
# Keep only the allocated sections of `size -A` (drop debug and attribute sections).
string(REGEX REPLACE "\n\\.(debug|comment|ARM\\.attributes)[^\n]*" "" sections "${sections}")
file(WRITE ${REPORT} "${summary}\n\n${sections}")
message(STATUS "${summary}")

set(over "")
if(flash GREATER FLASH_BUDGET)
  string(APPEND over " flash ${flash} > ${FLASH_BUDGET};")
endif()
if(ram GREATER RAM_BUDGET)
  string(APPEND over " RAM ${ram} > ${RAM_BUDGET};")
endif()
if(over)
  file(REMOVE ${REPORT})
  message(FATAL_ERROR "${name} is over its budget:${over} see docs/firmware.md")
endif()
