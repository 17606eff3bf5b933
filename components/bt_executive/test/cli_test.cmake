# End-to-end test of `cairn-bt`: golden trace, exit codes, one-line load errors, log + replay.
# Invoked by ctest with -DCAIRN_BT=<exe> -DDATA=<test/data> (tmp files go to the current directory).
function(run_bt expected_rc out_var err_var)
  execute_process(COMMAND ${CAIRN_BT} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL expected_rc)
    message(FATAL_ERROR "cairn-bt ${ARGN}: exit ${rc}, expected ${expected_rc}\n${out}\n${err}")
  endif()
  set(${out_var} "${out}" PARENT_SCOPE)
  set(${err_var} "${err}" PARENT_SCOPE)
endfunction()

file(READ ${DATA}/trace_demo.expected expected)

# Golden trace (simulated step clock, no sleeping) and the same on the real 20 ms schedule: identical.
run_bt(0 out err run ${DATA}/trace_demo.xml --trace --no-wait)
if(NOT out STREQUAL expected)
  message(FATAL_ERROR "trace differs from trace_demo.expected:\n${out}")
endif()
run_bt(0 out err run ${DATA}/trace_demo.xml --trace --period-ms 20)
if(NOT out STREQUAL expected)
  message(FATAL_ERROR "trace with real periods differs:\n${out}")
endif()

# Step limit: still RUNNING.
run_bt(3 out err run ${DATA}/trace_demo.xml --max-ticks 2 --no-wait)
if(NOT out STREQUAL "RESULT RUNNING\n")
  message(FATAL_ERROR "max-ticks: ${out}")
endif()

# --tree selects a tree; FAILURE -> exit 1; run-time script errors are warnings on stderr.
run_bt(1 out err run ${DATA}/success.xml --tree Check --no-wait)
if(NOT out STREQUAL "RESULT FAILURE\n" OR NOT err MATCHES "warning: ScriptCondition: script: blackboard entry 'n' is unset")
  message(FATAL_ERROR "--tree Check: ${out} ${err}")
endif()
run_bt(0 out err run ${DATA}/success.xml --no-wait)

# Load errors: one line, file:line, exit 2.
run_bt(2 out err run ${DATA}/cycle.xml)
if(NOT err STREQUAL "cairn: ${DATA}/cycle.xml:10: SubTree cycle: A -> B -> A\n")
  message(FATAL_ERROR "cycle error: ${err}")
endif()
run_bt(2 out err run ${DATA}/bad_port.xml)
if(NOT err MATCHES "^cairn: .*/bad_port.xml:4: type mismatch in port 'msec' \\(int\\)")
  message(FATAL_ERROR "bad port error: ${err}")
endif()
run_bt(2 out err run ${DATA}/does_not_exist.xml)

# Log file + replay reproduce the trace.
run_bt(0 out err run ${DATA}/trace_demo.xml --no-wait --log bt_cli_test.log)
run_bt(0 out err replay bt_cli_test.log)
string(REPLACE "RESULT SUCCESS\n" "" expected_no_result "${expected}")
if(NOT out STREQUAL expected_no_result)
  message(FATAL_ERROR "replay differs:\n${out}")
endif()
run_bt(0 out err watch bt_cli_test.log)
if(NOT out MATCHES "step 5\nFallback  SUCCESS\n  Sequence  IDLE")
  message(FATAL_ERROR "watch output:\n${out}")
endif()

# psbt-eval (small run): the table, the PSBT - GM line and a synthesized tree as BT XML.
run_bt(0 out err psbt-eval --starts 3 --seed 2 --xml bt_cli_psbt.xml)
if(NOT out MATCHES "PSBT +0\\.[0-9]+" OR NOT out MATCHES "PSBT - GM at 140 s: [-+][0-9.]+ %" OR NOT out MATCHES "1457 candidate trees")
  message(FATAL_ERROR "psbt-eval output:\n${out}")
endif()
file(READ bt_cli_psbt.xml psbt_xml)
if(NOT psbt_xml MATCHES "<BehaviorTree ID=\"PersonSearch\">" OR NOT psbt_xml MATCHES "<Fallback name=\"search\">")
  message(FATAL_ERROR "psbt xml:\n${psbt_xml}")
endif()
# It names the runtime's person-search actions, which `run` (built-ins only) rejects at load.
run_bt(2 out err run bt_cli_psbt.xml)
if(NOT err MATCHES "unknown node '(WaitForPerson|SearchPerson)'")
  message(FATAL_ERROR "psbt xml run: ${err}")
endif()
