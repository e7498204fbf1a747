# cmake -DLCM_GEN=... -DOUT=.../qrtplan/lcmtypes -DTYPES="a.lcm;b.lcm" -P:
# lcm-gen's Python package "qrtplan" (relative imports only) copied as OUT,
# made afresh so a removed type does not linger in its __init__.py.
set(tmp ${OUT}.gen)
file(REMOVE_RECURSE ${OUT} ${tmp})
file(MAKE_DIRECTORY ${tmp})
execute_process(COMMAND ${LCM_GEN} -p --ppath ${tmp} ${TYPES}
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "lcm-gen failed (${rc})")
endif()
file(RENAME ${tmp}/qrtplan ${OUT})
file(REMOVE_RECURSE ${tmp})
