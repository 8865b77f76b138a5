/*
 * firmware/sim/hooks.h — the instrumentation of the simulation and bench
 * images: the bodies of main.c's hooks (firmware/hooks.h), included by
 * main.c after its state when FW_SIM is defined (toolchain/firmware.py
 * builds kind "sim" and "bench" with it). Never in the production image.
 *
 *   FW_SIM        text output and stop through the uCsim simulator interface
 *                 (sim_io.c): after FW_SIM_BLOCKS accepted blocks, or after
 *                 FW_SIM_SAMPLES accepted sample records (0: that count does
 *                 not stop), the link statistics are printed and s51 stops.
 *   FW_SIM_MODEL  the ADC inputs come from the TLC2543 + gyro model behind
 *                 the driver's pins (fw_sim.h, tlc_hal_sim.h, tlc_model.c):
 *                 its clock steps before every scan, its checks after.
 *   FW_SIM_TRACE  every byte received and every poll result on the output.
 *   FW_BENCH      machine-cycle counters of the scan and the link work
 *                 (production pins, s51's pins read 1: a failed self-test
 *                 is skipped so that the bench samples).
 *
 * Everything here lives in SFR cells the C51 core does not implement
 * (uCsim keeps them as memory), so the images keep the production image's
 * RAM use; the helpers run where main has no live locals.
 */
#ifndef FW_SIM_HOOKS_H
#define FW_SIM_HOOKS_H

#include "sim/sim_io.h"
#if defined(FW_SIM_MODEL)
#include "sim/fw_sim.h" /* ADC inputs from the TLC2543 + gyro model */
#endif

#ifndef FW_SIM_BLOCKS
#define FW_SIM_BLOCKS 0 /* 0: the block count does not stop the run */
#endif
#ifndef FW_SIM_SAMPLES
#define FW_SIM_SAMPLES 0 /* 0: the sample count does not stop the run */
#endif

#if defined(FW_BENCH) || FW_AIDED
/* Machine-cycle timestamp (16 bits, wraps every 65536 cycles = 71 ms):
 * TH0:TL0, read high-low-high so a carry between the reads is seen. */
static uint16_t cycles_now(void)
{
    uint8_t h, l;
    do {
        h = TH0;
        l = TL0;
    } while (h != TH0);
    return (uint16_t)(((uint16_t)h << 8) | l);
}
#endif

#if defined(FW_BENCH)

/* Bench counters (machine cycles from cycles_now()). They live in SFR cells
 * the C51 core does not implement (uCsim keeps them as memory), so the
 * bench image has the production image's RAM use; the helpers are called
 * where main has no live locals. */
__sfr16 __at(0xD2D1) bench_scan_min;
__sfr16 __at(0xD4D3) bench_scan_max;
__sfr16 __at(0xD6D5) bench_scans;
__sfr32 __at(0xDCDBDAD9) bench_scan_sum;
__sfr16 __at(0xDEDD) bench_blocks;
__sfr16 __at(0xE2E1) bench_busy_block; /* CPU cycles of link handling, block in progress */
__sfr16 __at(0xE4E3) bench_busy_max;
__sfr16 __at(0xE6E5) bench_t_start; /* block started */
__sfr16 __at(0xE9E8) bench_t_syn;   /* 0xAA handed out */
__sfr16 __at(0xEBEA) bench_t_sum;   /* checksum handed out */
__sfr16 __at(0xEDEC) bench_sent;    /* tx.stats.blocks_sent seen last */
__sfr16 __at(0xEFEE) bench_t_loop;  /* start of this loop iteration */
__sfr16 __at(0xD8D7) bench_t_scan;
__sfr __at(0xBE) bench_busy; /* this iteration did link work */
__sfr32 __at(0xF4F3F2F1) bench_busy_sum;
__sfr32 __at(0xF9F8F7F6) bench_exch_sum;     /* block start -> accepted */
__sfr32 __at(0xBCBBBAB9) bench_syn_wait_sum; /* 0xAA handed out -> 0xBB received */
__sfr32 __at(0xFDFCFBFA) bench_ans_wait_sum; /* checksum handed out -> answer received */
/* link v2: cycles of the polls that handed out a byte */
__sfr16 __at(0xA2A1) bench_poll_max;
__sfr16 __at(0xA4A3) bench_polls;
__sfr16 __at(0xA6A5) bench_poll_sum16; /* sum of cycles / 16 (wraps after ~3000 polls) */
__sfr16 __at(0xB3B2) bench_t_poll;
#if FW_AIDED
/* The aided board's CPU load. The iterations of the main loop that did
 * nothing (no byte received or sent, no poll result but NONE or IDLE, no
 * scan) add their machine cycles, from their start to the next one's, to
 * bench_idle; the firmware's ticks from the first iteration (bench_tick0)
 * to the end give the total: busy = 1 - idle / total. A busy iteration
 * pays for one timestamp only (the poll and block counters of the other
 * bench images are off), so the figure is the production loop's. More
 * cells the C52 core leaves free. */
__sfr32 __at(0xCFCE9F9E) bench_idle;
__sfr16 __at(0xB7B1) bench_t_prev;
__sfr16 __at(0x9B9A) bench_tick0;
__sfr __at(0x97) bench_started;
#if defined(FW_PROFILE) && !(defined(FW_BENCH) && FW_AIDED)
#error "FW_PROFILE is a variant of the aided board's bench image"
#endif
#if defined(FW_PROFILE)
/* Profile (bench/aided.py's profile run, -DFW_PROFILE: its timestamps
 * inflate the busy figure, so the load runs go without): machine cycles
 * of the sender's polls that sent a byte / did not, of its sink calls,
 * and their counts. Some of these cells are the device model's in a sim
 * image (tlc_hal_sim.h, tlc_model.c); a bench image has no model. */
__sfr32 __at(0xC3C2C1C0) prof_send;
__sfr32 __at(0xC7C6C5C4) prof_other;
__sfr32 __at(0xACABAAA9) prof_rx;
__sfr16 __at(0x9493) prof_nsend;
__sfr16 __at(0xAEAD) prof_nframe;
__sfr16 __at(0x9695) prof_nrx;
__sfr16 __at(0x9D9C) prof_t;
__sfr __at(0xBF) prof_r;
#endif
#endif

static void bench_init(void)
{
    bench_scan_min = 0xFFFFu;
    bench_scan_max = 0;
    bench_scans = 0;
    bench_scan_sum = 0;
    bench_blocks = 0;
    bench_busy_block = 0;
    bench_busy_max = 0;
    bench_sent = 0;
    bench_busy_sum = 0;
    bench_exch_sum = 0;
    bench_syn_wait_sum = 0;
    bench_ans_wait_sum = 0;
#if FW_AIDED
    bench_idle = 0;
    bench_started = 0;
#if defined(FW_PROFILE)
    prof_send = 0;
    prof_other = 0;
    prof_rx = 0;
    prof_nsend = 0;
    prof_nframe = 0;
    prof_nrx = 0;
#endif
#endif
#if FW_LINK_V2
    bench_poll_max = 0;
    bench_polls = 0;
    bench_poll_sum16 = 0;
#endif
}

static void bench_loop_start(void)
{
    bench_t_loop = cycles_now();
#if FW_AIDED
    if (!bench_started) {
        bench_started = 1;
        bench_tick0 = fw_ticks;
    } else if (!bench_busy) {
        bench_idle += (uint16_t)(bench_t_loop - bench_t_prev);
    }
    bench_t_prev = bench_t_loop;
#endif
    bench_busy = 0;
}

static void bench_loop_end(void)
{
    if (bench_busy) {
        bench_busy_block += (uint16_t)(cycles_now() - bench_t_loop);
    }
}

#if FW_LINK_V2
/* Link v2: machine cycles of each poll that handed out a byte (the CPU
 * the sender spends per byte sent: compare with a byte time, 960 cycles at
 * 9600 baud), in more unimplemented SFR cells. */
static void bench_poll_end(int st)
{
    uint16_t d = (uint16_t)(cycles_now() - bench_t_poll);
    if (st == ATT_LINK2_SEND) {
        if (d > bench_poll_max) {
            bench_poll_max = d;
        }
        bench_polls++;
        bench_poll_sum16 += (uint16_t)(d >> 4);
    }
}
/* Link v2: the link work is counted (busy), the exchange per record runs
 * from its block start to its acknowledgement (not traced per byte). */
static void bench_rx(uint8_t b)
{
    (void)b;
    bench_busy = 1;
}
static void bench_tx(void)
{
    bench_busy = 1;
}
#else
static void bench_rx(uint8_t b)
{
    bench_busy = 1;
    if (b == (uint8_t)ATT_LINK_SYN_ACK) {
        bench_syn_wait_sum += (uint16_t)(bench_t_loop - bench_t_syn);
    } else if (b == (uint8_t)ATT_LINK_ACK || b == (uint8_t)ATT_LINK_NAK) {
        bench_ans_wait_sum += (uint16_t)(bench_t_loop - bench_t_sum);
    }
}

static void bench_tx(void)
{
    bench_busy = 1;
    if (tx.stats.blocks_sent != bench_sent) { /* the checksum was handed out */
        bench_sent = tx.stats.blocks_sent;
        bench_t_sum = bench_t_loop;
    } else if (txb == (uint8_t)ATT_LINK_SYN && tx.index == 0u) {
        bench_t_syn = bench_t_loop;
    }
}

#endif /* FW_LINK_V2 */
static void bench_block_start(void)
{
    bench_busy = 1;
    bench_t_start = bench_t_loop;
    bench_busy_block = 0;
}

static void bench_scan_begin(void)
{
    bench_busy = 1;
    bench_t_scan = cycles_now();
}

static void bench_scan_end(void)
{
    uint16_t c = (uint16_t)(cycles_now() - bench_t_scan);
    if (c < bench_scan_min) {
        bench_scan_min = c;
    }
    if (c > bench_scan_max) {
        bench_scan_max = c;
    }
    bench_scan_sum += c;
    bench_scans++;
}

/* The accepted block's exchange and link work (inline: main's cost as it was). */
#define BENCH_ACCEPTED()                                            \
    do {                                                            \
        bench_exch_sum += (uint16_t)(cycles_now() - bench_t_start); \
        bench_busy_sum += bench_busy_block;                         \
        if (bench_busy_block > bench_busy_max) {                    \
            bench_busy_max = bench_busy_block;                      \
        }                                                           \
        bench_blocks++;                                             \
    } while (0)
#else
#define BENCH_ACCEPTED()
#endif /* FW_BENCH */

/* Instrumentation lives in SFR cells the C51 core does not implement
 * (uCsim keeps them as memory), so it takes none of the 128 bytes of RAM. */
#if defined(FW_SIM_C52)
__sfr16 __at(0x9291) sim_accepted; /* (0xC8-0xCD are Timer 2's on the C52 core) */
#else
__sfr16 __at(0xCECD) sim_accepted; /* blocks the receiver accepted (FW_SIM_BLOCKS) */
#endif
__sfr16 __at(0xB5B4) sim_samples; /* ... of them sample records (FW_SIM_SAMPLES) */

static void put_stat(const char *name)
{
    fw_sim_putc(' ');
    fw_sim_puts(name);
    fw_sim_putc('=');
}
#define STAT(name, v)                 \
    do {                              \
        put_stat(name);               \
        fw_sim_puthex((uint16_t)(v)); \
    } while (0)
#define STAT32(name, v)                       \
    do {                                      \
        put_stat(name);                       \
        fw_sim_puthex((uint16_t)((v) >> 16)); \
        fw_sim_puthex((uint16_t)(v));         \
    } while (0)

/* Final report of a simulation run (hex values), then stop. */
#if FW_LINK_V2
__sfr __at(0xA7) sim_bad_acks; /* ACK frames the sender dropped (CRC, length: a byte lost or changed) */
#endif
static void sim_finish(void)
{
    fw_sim_puts("STATS");
#if FW_LINK_V2
    STAT("accepted", sim_accepted); /* records acknowledged (link v2 keeps no statistics on the chip) */
    STAT("samples", seq);
    STAT("queued", att_link2_sender_pending(&tx));
    STAT("overrun_pending", ovr_count);
    STAT("ticks", fw_ticks);
    STAT("bad_acks", sim_bad_acks);
#else
    STAT("accepted", tx.stats.blocks_accepted);
    STAT("sent", tx.stats.blocks_sent);
    STAT("naks", tx.stats.naks);
    STAT("timeouts", tx.stats.timeouts);
    STAT("gave_up", tx.stats.gave_up);
    STAT("discarded", tx.stats.bytes_discarded);
    STAT("samples", seq);
    STAT("queued", (uint8_t)q_any + (uint8_t)q_full);
    STAT("overrun_pending", ovr_count);
    STAT("ticks", fw_ticks);
#endif
#if defined(FW_SIM_MODEL)
    STAT("conversions", fw_sim_conversions());
#endif
    fw_sim_putc('\n');
#if defined(FW_BENCH)
    fw_sim_puts("BENCH");
    STAT("scans", bench_scans);
    STAT("scan_min", bench_scan_min);
    STAT("scan_max", bench_scan_max);
    STAT32("scan_sum", bench_scan_sum);
    STAT("blocks", bench_blocks);
    STAT32("busy_sum", bench_busy_sum);
    STAT("busy_max", bench_busy_max);
    STAT32("exch_sum", bench_exch_sum);
    STAT32("syn_wait_sum", bench_syn_wait_sum);
    STAT32("ans_wait_sum", bench_ans_wait_sum);
#if FW_LINK_V2
    STAT("poll_max", bench_poll_max);
    STAT("polls", bench_polls);
    STAT("poll_sum16", bench_poll_sum16);
#endif
#if FW_AIDED
    STAT("tick0", bench_tick0);
    STAT("ticks", fw_ticks);
    STAT32("idle", bench_idle);
#if defined(FW_PROFILE)
    STAT32("psend", prof_send);
    STAT32("pother", prof_other);
    STAT32("prx", prof_rx);
    STAT("nsend", prof_nsend);
    STAT("nframe", prof_nframe);
    STAT("nrx", prof_nrx);
#endif
#endif
    fw_sim_putc('\n');
#endif
    fw_sim_stop(0);
}

#if FW_AIDED
/* "UART <cycles>": the machine cycles one byte takes on the line (Timer 2's
 * bit time x 10, 8N1): from one byte's end (the interrupt's tx_free) to the
 * end of the next, written at once; both are 0x00, link v2's frame
 * delimiter, which a receiver skips. */
static void sim_uart_zero(void)
{
    tx_free = 0;
    SBUF = 0;
    while (!tx_free) {
    }
}

static void sim_uart_time(void)
{
    uint16_t t;
    sim_uart_zero();
    t = cycles_now();
    sim_uart_zero();
    t = (uint16_t)(cycles_now() - t);
    fw_sim_puts("UART ");
    fw_sim_puthex(t);
    fw_sim_putc('\n');
}
#endif

static void sim_init(void)
{
    sim_accepted = 0;
    sim_samples = 0;
#if FW_LINK_V2
    sim_bad_acks = 0;
#endif
#if defined(FW_BENCH)
    bench_init();
#endif
#if defined(FW_SIM_MODEL)
    fw_sim_model_init();
#endif
#if FW_AIDED
    sim_uart_time();
#endif
#if FW_LINK_V2
    /* "CRC <hex>": the 8051's CRC-32C (link2_sender.c, in assembly there) of
     * the check string "123456789", nested calls (no RAM); the tests compare
     * it with 0xE3069283 (docs/link.md) */
#define SIM_CRC9                                                                                      \
    att_link2_crc_byte(                                                                               \
        att_link2_crc_byte(                                                                           \
            att_link2_crc_byte(                                                                       \
                att_link2_crc_byte(                                                                   \
                    att_link2_crc_byte(                                                               \
                        att_link2_crc_byte(                                                           \
                            att_link2_crc_byte(                                                       \
                                att_link2_crc_byte(att_link2_crc_byte(0xFFFFFFFFul, '1'), '2'), '3'), \
                            '4'),                                                                     \
                        '5'),                                                                         \
                    '6'),                                                                             \
                '7'),                                                                                 \
            '8'),                                                                                     \
        '9')
    fw_sim_puts("CRC ");
    fw_sim_puthex((uint16_t)(~SIM_CRC9 >> 16));
    fw_sim_puthex((uint16_t)~SIM_CRC9);
    fw_sim_putc('\n');
#undef SIM_CRC9
#endif
}

/* The block accepted last (queue[!q_head]): count it; stop after the configured
 * number (a count that is 0 costs nothing: the bench image measures main's own work). */
#if FW_SIM_BLOCKS != 0
#define SIM_COUNT_BLOCK()                                \
    do {                                                 \
        if (++sim_accepted >= (uint16_t)FW_SIM_BLOCKS) { \
            sim_finish();                                \
        }                                                \
    } while (0)
#else
#define SIM_COUNT_BLOCK()
#endif
#if FW_SIM_SAMPLES != 0 && FW_LINK_V2
#define SIM_COUNT_SAMPLE()                                                                        \
    do {                                                                                          \
        if (sim_rec[0] != (uint8_t)ATT_BLOCK_MARK && ++sim_samples >= (uint16_t)FW_SIM_SAMPLES) { \
            sim_finish();                                                                         \
        }                                                                                         \
    } while (0)
#elif FW_SIM_SAMPLES != 0
#define SIM_COUNT_SAMPLE()                                                                               \
    do {                                                                                                 \
        if (queue[!q_head][0] != (uint8_t)ATT_BLOCK_MARK && ++sim_samples >= (uint16_t)FW_SIM_SAMPLES) { \
            sim_finish();                                                                                \
        }                                                                                                \
    } while (0)
#else
#define SIM_COUNT_SAMPLE()
#endif

#if defined(FW_SIM_TRACE)
/* "r<byte>@<tick>" per byte received, "p<result> <byte>@<tick>" per poll that did something */
#define SIM_TRACE_RX(b)          \
    do {                         \
        fw_sim_putc('r');        \
        fw_sim_puthex(b);        \
        fw_sim_putc('@');        \
        fw_sim_puthex(fw_ticks); \
        fw_sim_putc('\n');       \
    } while (0)
#define SIM_TRACE_POLL(st)                                    \
    do {                                                      \
        if ((st) != ATT_LINK_NONE && (st) != ATT_LINK_IDLE) { \
            fw_sim_putc('p');                                 \
            fw_sim_puthex((uint16_t)(st));                    \
            fw_sim_putc(' ');                                 \
            fw_sim_puthex(txb);                               \
            fw_sim_putc('@');                                 \
            fw_sim_puthex(fw_ticks);                          \
            fw_sim_putc('\n');                                \
        }                                                     \
    } while (0)
#else
#define SIM_TRACE_RX(b)
#define SIM_TRACE_POLL(st)
#endif

#if FW_LINK_V2
/* Link v2: the records an ACK covered are the ring's slots from the old
 * base to the new one (still there: nothing is pushed before the main loop
 * comes back); each counts as one accepted block. sim_base0 and sim_rec
 * live in SFR cells, like the counters. */
__sfr __at(0xB6) sim_base0;
#if ATT_LINK2_ONE_RING_IDATA
#define sim_ring att_link2_one_ring
#else
#define sim_ring att_link2_one.ring
#endif
#define sim_rec (sim_ring + (uint8_t)(6u * (uint8_t)(sim_base0 & (uint8_t)(ATT_LINK2_ONE_RING - 1))))
static void sim_acked(void)
{
    while (sim_base0 != att_link2_one.base) {
        BENCH_ACCEPTED();
#if FW_SIM_BLOCKS != 0
        SIM_COUNT_BLOCK();
#else
        sim_accepted++; /* reported in STATS */
#endif
        SIM_COUNT_SAMPLE();
        sim_base0++;
    }
}
#if defined(FW_PROFILE)
#define FW_HOOK_V2_SINK(call)                         \
    do {                                              \
        sim_base0 = att_link2_one.base;               \
        prof_t = cycles_now();                        \
        prof_r = (call);                              \
        prof_rx += (uint16_t)(cycles_now() - prof_t); \
        prof_nrx++;                                   \
        if (prof_r == ATT_LINK2_FRAME) {              \
            prof_nframe++; /* a valid ACK */          \
        }                                             \
        if (prof_r == ATT_LINK2_BAD_FRAME) {          \
            sim_bad_acks++; /* e.g. a byte lost */    \
        }                                             \
        sim_acked();                                  \
    } while (0)
#else
#define FW_HOOK_V2_SINK(call)                      \
    do {                                           \
        sim_base0 = att_link2_one.base;            \
        if ((call) == ATT_LINK2_BAD_FRAME) {       \
            sim_bad_acks++; /* e.g. a byte lost */ \
        }                                          \
        sim_acked();                               \
    } while (0)
#endif
#endif

/* ---- the hooks (firmware/hooks.h lists them) ---- */
#define FW_HOOK_INIT() sim_init()
#define FW_HOOK_ACCEPTED()  \
    do {                    \
        BENCH_ACCEPTED();   \
        SIM_COUNT_BLOCK();  \
        SIM_COUNT_SAMPLE(); \
    } while (0)
#if defined(FW_PROFILE)
#define FW_HOOK_POLL_BEGIN() (bench_t_poll = cycles_now())
#define FW_HOOK_POLL(st)                                        \
    do {                                                        \
        bench_t_poll = (uint16_t)(cycles_now() - bench_t_poll); \
        if ((st) == ATT_LINK2_SEND) {                           \
            prof_send += bench_t_poll;                          \
            prof_nsend++;                                       \
        } else {                                                \
            prof_other += bench_t_poll;                         \
        }                                                       \
        if ((st) != ATT_LINK2_NONE && (st) != ATT_LINK2_IDLE) { \
            bench_busy = 1; /* the sender did something */      \
        }                                                       \
    } while (0)
#elif defined(FW_BENCH) && FW_AIDED
#define FW_HOOK_POLL_BEGIN()
#define FW_HOOK_POLL(st)                                        \
    do {                                                        \
        if ((st) != ATT_LINK2_NONE && (st) != ATT_LINK2_IDLE) { \
            bench_busy = 1; /* the sender did something */      \
        }                                                       \
    } while (0)
#elif defined(FW_BENCH) && FW_LINK_V2
#define FW_HOOK_POLL_BEGIN() (bench_t_poll = cycles_now())
#define FW_HOOK_POLL(st)    \
    do {                    \
        bench_poll_end(st); \
        SIM_TRACE_POLL(st); \
    } while (0)
#else
#define FW_HOOK_POLL_BEGIN()
#define FW_HOOK_POLL(st) SIM_TRACE_POLL(st)
#endif
#if defined(FW_BENCH)
#define FW_HOOK_LOOP_START() bench_loop_start()
#if FW_AIDED
#define FW_HOOK_LOOP_END()
#else
#define FW_HOOK_LOOP_END() bench_loop_end()
#endif
#define FW_HOOK_RX(b)    \
    do {                 \
        bench_rx(b);     \
        SIM_TRACE_RX(b); \
    } while (0)
#define FW_HOOK_TX()              bench_tx()
#define FW_HOOK_BLOCK_START()     bench_block_start()
/* s51's port pins read 1: the self-test fails, but it ran (its stack depth
 * is measured); the bench goes on to sample: the slot is given back, 1 */
#define FW_HOOK_SELFTEST_FAILED() (q_unpush(), 1)
#else
#define FW_HOOK_LOOP_START()
#define FW_HOOK_LOOP_END()
#define FW_HOOK_RX(b) SIM_TRACE_RX(b)
#define FW_HOOK_TX()
#define FW_HOOK_BLOCK_START()
#define FW_HOOK_SELFTEST_FAILED() 0
#endif
#if defined(FW_SIM_MODEL) && defined(FW_BENCH)
#define FW_HOOK_SCAN_BEGIN() \
    do {                     \
        fw_sim_model_step(); \
        bench_scan_begin();  \
    } while (0)
#define FW_HOOK_SCAN_END()    \
    do {                      \
        bench_scan_end();     \
        fw_sim_model_check(); \
    } while (0)
#elif defined(FW_SIM_MODEL)
#define FW_HOOK_SCAN_BEGIN() fw_sim_model_step()
#define FW_HOOK_SCAN_END()   fw_sim_model_check()
#elif defined(FW_BENCH)
#define FW_HOOK_SCAN_BEGIN() bench_scan_begin()
#define FW_HOOK_SCAN_END()   bench_scan_end()
#else
#define FW_HOOK_SCAN_BEGIN()
#define FW_HOOK_SCAN_END()
#endif
#if defined(FW_SIM_MODEL)
#define FW_HOOK_SELFTEST_END() fw_sim_model_check()
#else
#define FW_HOOK_SELFTEST_END()
#endif

#endif /* FW_SIM_HOOKS_H */
