/*
 * firmware/hooks.h — the points where main.c's build variants hook in. In
 * the production image (none of FW_SIM, FW_BENCH, FW_SIM_MODEL, FW_SIM_TRACE
 * defined) every hook is empty: main.c is then exactly the chip's firmware.
 * The simulation and bench images (FW_SIM, built by toolchain/firmware.py)
 * take the bodies from firmware/sim/hooks.h.
 *
 *   FW_HOOK_INIT()             after the timers and the UART are set up
 *   FW_HOOK_LOOP_START()       top of every main-loop iteration
 *   FW_HOOK_RX(b)              byte b received, before the link sender sees it
 *   FW_HOOK_POLL_BEGIN()       link v2: right before the sender's poll
 *   FW_HOOK_POLL(st)           the link sender's poll returned st
 *   FW_HOOK_V2_SINK(call)      link v2: wraps the sender's sink call (its
 *                              result is ignored in production)
 *   FW_HOOK_TX()               a byte went to the UART
 *   FW_HOOK_BLOCK_START()      the link sender took up the head block
 *   FW_HOOK_LOOP_END()         after the link work of an iteration
 *   FW_HOOK_ACCEPTED()         the receiver accepted the block queue[!q_head]
 *   FW_HOOK_SCAN_BEGIN()       right before an X/Y/Z scan
 *   FW_HOOK_SCAN_END()         right after it
 *   FW_HOOK_SELFTEST_END()     after the ADC self-test's conversions
 *   FW_HOOK_SELFTEST_FAILED()  a failed self-test was reported: the value main
 *                              returns (0: retry later; 1: sample anyway)
 */
#ifndef FW_HOOKS_H
#define FW_HOOKS_H

#if defined(FW_SIM)
#include "sim/hooks.h"
#elif defined(FW_BENCH) || defined(FW_SIM_MODEL) || defined(FW_SIM_TRACE)
#error "FW_BENCH, FW_SIM_MODEL and FW_SIM_TRACE are variants of the simulation image: define FW_SIM too"
#else
#define FW_HOOK_INIT()
#define FW_HOOK_LOOP_START()
#define FW_HOOK_RX(b)
#define FW_HOOK_POLL_BEGIN()
#define FW_HOOK_POLL(st)
#define FW_HOOK_V2_SINK(call) (void)(call)
#define FW_HOOK_TX()
#define FW_HOOK_BLOCK_START()
#define FW_HOOK_LOOP_END()
#define FW_HOOK_ACCEPTED()
#define FW_HOOK_SCAN_BEGIN()
#define FW_HOOK_SCAN_END()
#define FW_HOOK_SELFTEST_END()
#define FW_HOOK_SELFTEST_FAILED() 0
#endif

#endif /* FW_HOOKS_H */
