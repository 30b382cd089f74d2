# The manual page, rtsim.1: what `rtsim --man` prints (the usage and every
# command's --help-full as roff), written whole or not at all.
# Usage: cmake -DRTSIM=<the program> -DOUT=<rtsim.1> -P man.cmake
execute_process(COMMAND ${RTSIM} --man OUTPUT_FILE ${OUT}.tmp RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  file(REMOVE ${OUT}.tmp)
  message(FATAL_ERROR "rtsim --man failed (${rc})")
endif()
file(RENAME ${OUT}.tmp ${OUT})
