# hmc_warnings(target): the project's warning set, errors when HMC_WERROR is on (CI).
function(hmc_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wconversion -Wsign-conversion
                                           -Wshadow -Wcast-align)
  if(HMC_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# hmc_test(name sources...): a Catch2 test binary registered with ctest.
function(hmc_test name)
  add_executable(${name} ${ARGN})
  target_link_libraries(${name} PRIVATE hmc_test_main)
  hmc_warnings(${name})
  add_test(NAME ${name} COMMAND ${name})
endfunction()
