# Checks of a built firmware image, run by the build (cmake -P) after linking; the build fails
# on any of them. They hold the start-up and fault-record fixes (docs/firmware.md, "What runs",
# "Reset cause and fault record") and the board variant's info text in the shipped bytes:
#   - the reset vector is reset_handler, whose first instruction is `cpsid i` (0xB672);
#   - HardFault, NMI and every peripheral vector without a handler of its own go to
#     unexpected_interrupt (the fault recorder); every vector entry points into the image or
#     into its code copied to RAM (.ramfunc: the step interrupt);
#   - the fault record lies in .noinit: after .bss (not zeroed at start-up), below the stack;
#   - the image carries "hmc-board:<HMC_BOARD>;" in its .hmc_board_info section.
# Inputs: NM (arm-none-eabi-nm), ELF, BIN, BASE (the link address, e.g. 0x2000), BOARD.
foreach(var NM ELF BIN BASE BOARD)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "image_check.cmake: ${var} is not set")
  endif()
endforeach()

execute_process(COMMAND ${NM} ${ELF} OUTPUT_VARIABLE symbols RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "image_check.cmake: ${NM} failed on ${ELF}")
endif()

# symbol(NAME OUT): the symbol's address as a number.
function(symbol name out)
  string(REGEX MATCH "(^|\n)([0-9a-f]+) [A-Za-z] ${name}(\n|$)" found "${symbols}")
  if(NOT found)
    message(FATAL_ERROR "image_check.cmake: ${ELF} has no symbol ${name}")
  endif()
  math(EXPR value "0x${CMAKE_MATCH_2}")
  set(${out} ${value} PARENT_SCOPE)
endfunction()

# word(OFFSET OUT): the little-endian 32-bit word at OFFSET of the .bin.
function(word offset out)
  file(READ ${BIN} hex OFFSET ${offset} LIMIT 4 HEX)
  string(SUBSTRING "${hex}" 6 2 b3)
  string(SUBSTRING "${hex}" 4 2 b2)
  string(SUBSTRING "${hex}" 2 2 b1)
  string(SUBSTRING "${hex}" 0 2 b0)
  math(EXPR value "0x${b3}${b2}${b1}${b0}")
  set(${out} ${value} PARENT_SCOPE)
endfunction()

function(fail message)
  message(FATAL_ERROR "image_check.cmake: ${ELF}: ${message}")
endfunction()

file(SIZE ${BIN} size)
math(EXPR base "${BASE}")
math(EXPR end "${base} + ${size}")
symbol(reset_handler reset)
symbol(unexpected_interrupt recorder)
symbol(__ramfunc_start__ ramfunc_start)  # code copied to RAM at start-up (samd21_sections.ld)
symbol(__ramfunc_end__ ramfunc_end)

# The vector table: 16 system entries and 28 peripheral ones.
word(4 reset_vector)
math(EXPR want "${reset} | 1")
if(NOT reset_vector EQUAL want)
  fail("the reset vector is not reset_handler")
endif()
math(EXPR recorder_vector "${recorder} | 1")
foreach(entry 2 3)  # NMI, HardFault
  math(EXPR at "4 * ${entry}")
  word(${at} vector)
  if(NOT vector EQUAL recorder_vector)
    fail("vector ${entry} (NMI/HardFault) does not go to unexpected_interrupt, the fault recorder")
  endif()
endforeach()
foreach(entry RANGE 1 43)
  math(EXPR at "4 * ${entry}")
  word(${at} vector)
  if(vector EQUAL 0)
    continue()
  endif()
  math(EXPR target "${vector} & ~1")
  math(EXPR thumb "${vector} & 1")
  set(in_image FALSE)
  if(NOT target LESS base AND target LESS end)
    set(in_image TRUE)
  elseif(NOT target LESS ramfunc_start AND target LESS ramfunc_end)
    set(in_image TRUE)
  endif()
  if(NOT in_image OR NOT thumb EQUAL 1)
    fail("vector ${entry} points outside the image (or its code in RAM) or to ARM code")
  endif()
endforeach()

# The first instruction of the reset handler: cpsid i.
math(EXPR reset_offset "${reset} - ${base}")
file(READ ${BIN} first OFFSET ${reset_offset} LIMIT 2 HEX)
if(NOT first STREQUAL "72b6")
  fail("the reset handler's first instruction is 0x${first} (bytes), not cpsid i (72b6)")
endif()

# The fault record survives start-up: after .bss, below the stack.
string(REGEX MATCH "(^|\n)([0-9a-f]+) [bBdD] [^\n]*fault_record[^\n]*" found "${symbols}")
if(NOT found)
  fail("no fault record symbol")
endif()
math(EXPR record "0x${CMAKE_MATCH_2}")
symbol(__bss_end__ bss_end)
symbol(__stack_top__ stack_top)
if(record LESS bss_end OR NOT record LESS stack_top)
  fail("the fault record is not in .noinit (after .bss): start-up would clear it")
endif()

# The board variant's info text (file(STRINGS) escapes its semicolons, hence [^a-z]+ between).
file(STRINGS ${BIN} info REGEX "hmc-board:")
if(NOT info MATCHES "^hmc-board:${BOARD}[^a-z]+protocol:[0-9]+[^a-z]+firmware:[0-9]+[^a-z]+guessed:")
  fail("the image does not carry 'hmc-board:${BOARD};...' (found: '${info}')")
endif()

message(STATUS "${ELF}: image checks passed (cpsid i first, fault vectors, .noinit record, board '${BOARD}')")
