/*
 * firmware/main.c — AT89S51 acquisition board of the paper (sec. 3.1, 3.3):
 * samples the X, Y, Z gyro channels through the TLC2543 at a fixed period
 * paced by Timer 0 and sends each sample to the Linux computer with the
 * handshake protocol (link sender A of libattitude).
 *
 * Built with SDCC for the 8051 small model from the library's own sources,
 * unchanged: csrc/src/tlc2543.c (ADC driver), csrc/src/link_sender.c and
 * csrc/src/block.c (the block format's encoders, attitude/block.h). With
 * FW_LINK_V2 (config.h) the link is v2 instead: csrc/src/link2_sender.c in
 * its single-instance build (ATT_LINK2_ONE), the queue is its ring.
 * With FW_AIDED (config.h: the aided AT89S52 board, link v2) each sample is
 * a group of up to nine channels (gyros, accelerometer, magnetometer: one
 * TLC2543 scan, three records; csrc/src/block_channels.c adds the CHANNELS
 * report), the UART runs on Timer 2 and received bytes on an interrupt.
 * See docs/firmware.md for the wiring, the block formats and the build.
 *
 *   Timer 0  mode 1, free-running: TH0 advances every 256 machine cycles
 *            (1/3600 s at 11.0592 MHz), the firmware's tick. No interrupts
 *            at all: the firmware is one polled loop.
 *   Timer 1  mode 2 (auto-reload): UART baud-rate generator.
 *   UART     mode 1 (8N1), polled: TI means "transmitter free".
 *   P1.0-4   TLC2543 (EOC, I/O CLOCK, DATA IN, DATA OUT, CS), driven by the
 *            driver's HAL macros. P3.5: fault LED (low = on). P1.5-P1.7 stay
 *            free for in-system programming (MOSI, MISO, SCK).
 *
 * Main loop (never blocks longer than one X/Y/Z scan):
 *   1. a received byte goes to the link sender (sink);
 *   2. when the transmitter is free, the sender is polled: a byte to send,
 *      a timeout, a give-up, or idle (then the next queued block starts);
 *   3. when the sampling period has elapsed, one X/Y/Z scan is queued.
 * Blocks wait in a two-slot FIFO (one being sent, one being filled: all the
 * RAM allows next to the driver and the link sender). Every sample that cannot be
 * delivered is replaced by a report block at its place in the stream
 * (attitude/block.h), so the receiver always knows which sample is which.
 *
 * Integer arithmetic only, no dynamic memory, no __xdata.
 */
#include "config.h" /* FW_LINK_V2, FW_AIDED */
#if FW_AIDED
#include <8052.h> /* Timer 2 */
#else
#include <8051.h>
#endif

#include "attitude/block.h"
#if FW_LINK_V2
#include "attitude/link2.h"
#else
#include "attitude/link.h"
#endif
#include "attitude/tlc2543.h"
#include "config.h"

/* BOOT announces the period in ticks of 1/ATT_BLOCK_TICK_HZ s: the
 * firmware's tick must be that unit (it is at 11.0592 MHz). */
typedef char fw_tick_is_the_boot_period_unit[(FW_TICK_HZ == (long)ATT_BLOCK_TICK_HZ) ? 1 : -1];

/* ---- time base: Timer 0 ---------------------------------------------- */

/* Timer 0 runs free in mode 1 (16 bits) and counts machine cycles, so TH0
 * advances once every 256 machine cycles: 1/3600 s at 11.0592 MHz, the
 * firmware's tick. No interrupt (no stack, no CPU time): the main loop
 * folds TH0 into a 16-bit tick counter, which only needs it to come round
 * at least once every 255 ticks (71 ms); it comes round every few hundred
 * machine cycles. fw_ticks is not static: the simulation's device model
 * reads it as its clock. */
uint16_t fw_ticks; /* its low byte is always the TH0 value last folded in */

static uint16_t tick_now(void)
{
    uint8_t d = (uint8_t)(TH0 - (uint8_t)fw_ticks); /* ticks since the last call */
    fw_ticks += d;
    return fw_ticks;
}

/* ---- UART: mode 1, Timer 1 mode 2 ----------------------------------- */

#if FW_AIDED
/* The aided board: Timer 2 clocks the UART (RCLK = TCLK = 1, auto-reload
 * from RCAP2: config.h), and the serial interrupt moves each received byte
 * into a FIFO (at 115200 baud a byte comes every 80 machine cycles, less
 * than one poll of the sender or a scan) and turns TI into tx_free, which
 * the main loop polls instead of TI. */
static uint8_t __idata rxq[FW_RXQ];
static volatile uint8_t __idata rxq_in; /* written by the interrupt only */
static uint8_t __idata rxq_out;
static volatile __bit tx_free; /* the transmitter can take a byte */
#define TX_FREE tx_free

void uart_isr(void) __interrupt(4)
{
    if (RI) {
        RI = 0;
        rxq[rxq_in & (uint8_t)(FW_RXQ - 1)] = SBUF; /* a full FIFO loses the oldest byte: an ACK */
        rxq_in++;                                   /* frame fails its CRC, the next one frees the records */
    }
    if (TI) {
        TI = 0;
        tx_free = 1;
    }
}

static void uart_init(void)
{
    SCON = 0x50; /* mode 1 (8-bit UART, variable baud), REN = 1 */
    RCAP2H = (unsigned char)((uint16_t)FW_RCAP2 >> 8);
    RCAP2L = (unsigned char)FW_RCAP2;
    TH2 = (unsigned char)((uint16_t)FW_RCAP2 >> 8);
    TL2 = (unsigned char)FW_RCAP2;
    T2CON = 0x34; /* RCLK = TCLK = 1 (Timer 2 is the baud generator both ways), TR2 = 1 */
    tx_free = 1;
    ES = 1;
    EA = 1;
}
#else
#define TX_FREE TI

static void uart_init(void)
{
    SCON = 0x50;                                    /* mode 1 (8-bit UART, variable baud), REN = 1 */
    TMOD = (unsigned char)((TMOD & 0x0Fu) | 0x20u); /* Timer 1: mode 2, timer */
    TH1 = (unsigned char)FW_TH1;
    TL1 = (unsigned char)FW_TH1;
#if FW_SMOD
    PCON |= 0x80u; /* SMOD = 1: double baud rate */
#else
    PCON &= 0x7Fu;
#endif
    TR1 = 1;
    TI = 1; /* "transmitter free": the main loop polls TI before writing SBUF */
}
#endif /* FW_AIDED */

static void timer0_init(void)
{
    TMOD = (unsigned char)((TMOD & 0xF0u) | 0x01u); /* Timer 0: mode 1 (16-bit), timer */
    TH0 = 0;
    TL0 = 0;
    TR0 = 1; /* free-running; no interrupt */
}

/* ---- block queue ----------------------------------------------------- */

#if FW_LINK_V2
/* Link v2: the queue is the link sender's ring (ATT_LINK2_ONE_RING records,
 * kept until acknowledged). A block is written in place, in the ring slot
 * the next push fills (wp), then pushed. */
static uint16_t seq;       /* number of the next sample to take */
static uint16_t ovr_count; /* samples lost to a full ring, not yet reported:
                              always the newest ones, seq - ovr_count .. seq - 1 */
static uint8_t __data *wp; /* the block being written (a ring slot) */
static uint8_t txb;        /* byte handed out by the link sender (its out pointer is __data) */
#define tx att_link2_one   /* link_state.c */
static tlc2543 adc;

/* The ring slot for the next block (wp); 0 if the ring is full. */
static uint8_t q_push(void)
{
    wp = att_link2_sender_tail(&tx);
    return wp != 0;
}

/* The block at wp is complete: push it (it is in its slot already). */
#define q_commit() (void)att_link2_sender_push(&tx, wp)

/* The self-test passed: its slot is not needed (never pushed). */
#define q_unpush() ((void)0)

/* flush_overrun() waits for "the queue is empty": here, for an empty ring
 * (every record acknowledged). While samples are being lost nothing is
 * pushed, so the ring drains within one round trip; the report then goes
 * out at once and leaves the next samples 3 free slots. (Waiting for only
 * two free slots made each report the cause of the next loss when the
 * window was tight: at period 41 in s51 the stream settled into a sample
 * and a report in turn, 24 samples/s instead of 38; docs/link.md.) */
#define q_any (att_link2_sender_room(&tx) < (uint8_t)ATT_LINK2_ONE_RING)
#else
/* Everything in internal RAM (the small model's default space): __data
 * pointers are one byte and need no library call. */
static uint8_t queue[2][ATT_BLOCK_SIZE];
static __bit q_head;       /* slot of the oldest block (the one being sent) */
static __bit q_any;        /* at least one block queued */
static __bit q_full;       /* both slots used */
static __bit q_last;       /* slot q_push() claimed last */
static uint16_t seq;       /* number of the next sample to take */
static uint16_t slot_seq0; /* number of the sample in slot 0 / 1 */
static uint16_t slot_seq1;
static uint16_t ovr_count; /* samples lost to a full queue, not yet reported:
                              always the newest ones, seq - ovr_count .. seq - 1 */
static uint8_t __data *wp; /* the block being written */
static uint8_t txb;        /* byte handed out by the link sender (its out pointer is __data) */

extern att_link_sender fw_tx; /* link_state.c */
#define tx fw_tx
static tlc2543 adc;

#define q_commit() /* the block is in its slot already */

/* Claim the free slot at the tail (wp points to it); 0 if the queue is full. */
static uint8_t q_push(void)
{
    if (q_full) {
        return 0;
    }
    q_last = q_head ^ q_any;
    wp = queue[q_last];
    if (q_any) {
        q_full = 1;
    }
    q_any = 1;
    return 1;
}

/* Give back the slot q_push() claimed last. */
static void q_unpush(void)
{
    if (q_full) {
        q_full = 0;
    } else {
        q_any = 0;
    }
}

#endif /* FW_LINK_V2 */

/* Samples lost to a full queue are announced in their place (after every
 * earlier block, before every later one), once the queue is empty: the
 * report then leaves the other slot to the next sample, so a report never
 * causes the next loss. */
static void flush_overrun(void)
{
    if (!q_any && q_push()) {
        (void)att_block_encode_loss(wp, (uint8_t)ATT_BLOCK_OVERRUN, (uint16_t)(seq - ovr_count), ovr_count);
        q_commit();
        ovr_count = 0;
    }
}

/* Hooks of the build variants (firmware/hooks.h): empty in the production
 * image; the simulation and bench images' instrumentation (firmware/sim/hooks.h)
 * sees the state above. */
#include "hooks.h"

/* ---- ADC ------------------------------------------------------------- */

/* X, Y, Z in one scan, then power-down (address 14): the three channels
 * are converted within one scan (about 0.4 ms apart at most), not one
 * sampling period apart as with next = X, and the ADC sleeps in between. */
static const uint8_t xyz[3] = { TLC2543_CH_X, TLC2543_CH_Y, TLC2543_CH_Z };

/* Start of a sampling period: a free slot for the sample (wp), or 0 if
 * the queue is full: then the sample is lost (counted, announced later by
 * an OVERRUN report) and the ADC is not touched. */
static uint8_t sample_slot(void)
{
    if (ovr_count != 0u) {
        flush_overrun();
    }
    if (ovr_count != 0u || !q_push()) {
        ovr_count++;
        return 0;
    }
#if !FW_LINK_V2
    if (q_last) {
        slot_seq1 = seq;
    } else {
        slot_seq0 = seq;
    }
#endif
    return 1;
}

/* The scan into the slot at wp returned st: the sample record (the
 * codes, native words in the slot, encoded in place), or an ADC_ERROR
 * report when the scan (or the encoding: a code above 4095) failed. */
static void sample_store(int st)
{
    if (st == ATT_OK) {
        st = att_block_encode_sample(wp, (const uint16_t __data *)wp);
    }
    if (st != ATT_OK) {
        (void)att_block_encode_adc_error(wp, seq, (int8_t)st);
    }
    q_commit();
}

/* Power-up self-test of the ADC (its three internal test voltages), run
 * from main into a queue slot: the result st. A failure lights the fault
 * LED, is reported over the link and is retried every
 * FW_SELFTEST_RETRY_TICKS; sampling starts only once it passes (1). */
static uint8_t self_test_done(int st)
{
    uint8_t i;
    uint16_t bad = 0;
    if (st != ATT_OK) {
        /* the code of the failed test input (MID, REFM, REFP), 0 for
         * another error; the codes are the slot's three words */
        i = (uint8_t)(TLC2543_E_SELFTEST_MID - st);
        if (i < 3u) {
            bad = ((uint16_t __data *)wp)[i];
        }
        (void)att_block_encode_selftest(wp, (int8_t)st, bad, (uint8_t)seq); /* attempt, mod 256 */
        q_commit();
        P3_5 = 0;                         /* fault LED on */
        return FW_HOOK_SELFTEST_FAILED(); /* 0: retried after FW_SELFTEST_RETRY_TICKS */
    }
    q_unpush(); /* passed: the slot is not needed */
    P3_5 = 1;   /* fault LED off */
    return 1;
}

/* ---- link events ------------------------------------------------------ */
#if !FW_LINK_V2

/* The head block was accepted by the receiver: drop it from the queue. */
static void block_accepted(void)
{
    if (queue[q_head][0] != (uint8_t)ATT_BLOCK_MARK) {
        P3_5 = 1; /* a sample went through: fault LED off */
    }
    q_head = !q_head;
    q_unpush();
    FW_HOOK_ACCEPTED(); /* the accepted block is queue[!q_head] */
}

/* The link gave up on the head block. A sample is replaced in place by a
 * GAVE_UP report (sent next); a report stays and is sent again. */
static void block_given_up(void)
{
    P3_5 = 0; /* fault LED on */
    wp = queue[q_head];
    if (wp[0] != (uint8_t)ATT_BLOCK_MARK) {
        (void)att_block_encode_loss(wp, (uint8_t)ATT_BLOCK_GAVE_UP, q_head ? slot_seq1 : slot_seq0, 1u);
    }
}

/* ---- main ------------------------------------------------------------ */

static const att_link_sender_config link_cfg = { FW_SYN_TIMEOUT_TICKS, FW_ANSWER_TIMEOUT_TICKS,
                                                 ATT_BLOCK_SIZE, FW_MAX_ATTEMPTS };
#endif /* !FW_LINK_V2 */

#if FW_AIDED
/* The bytes from the receiver the interrupt put in the FIFO. */
static void link_rx(void)
{
    uint8_t b;
    while (rxq_out != rxq_in) {
        b = rxq[rxq_out & (uint8_t)(FW_RXQ - 1)];
        rxq_out++;
        FW_HOOK_RX(b);
        FW_HOOK_V2_SINK(att_link2_sender_sink(&tx, b, fw_ticks));
    }
}
#define LINK_RX() link_rx()
#elif FW_LINK_V2
/* A byte from the receiver, if one came. The UART holds one received byte
 * (SBUF, RI): one that completes while RI is still set is lost, and so is
 * the ACK it belongs to (its records are then freed only by the next ACK).
 * Bytes arrive every 960 machine cycles at 9600 baud; a poll (up to ~860)
 * and a scan (852) in one loop iteration would exceed that, so the loop
 * looks at RI before each of them and after the scan. (A function: two
 * more bytes of stack on the sink's path, which stays shallower than the
 * scan's; inlined three times it cost 33 bytes of flash.) */
static void link_rx(void)
{
    if (RI) {
        RI = 0;
        FW_HOOK_RX(SBUF);
        FW_HOOK_V2_SINK(att_link2_sender_sink(&tx, SBUF, fw_ticks));
    }
}
#define LINK_RX() link_rx()
#else
#define LINK_RX() ((void)0)
#endif

#if FW_AIDED
/* ---- the aided board's samples: groups ---------------------------------- */

#define FW_CHANNELS                                                \
    (ATT_BLOCK_CH_GYR | (FW_ACC_EVERY != 0 ? ATT_BLOCK_CH_ACC : 0) \
     | (FW_MAG_EVERY != 0 ? ATT_BLOCK_CH_MAG : 0))

/* The inputs of one scan: the gyros, then the accelerometer and the
 * magnetometer when due (the first 3, 6 or 9 of all[], or mag[]). */
static const uint8_t all[9] = { TLC2543_CH_X,   TLC2543_CH_Y, TLC2543_CH_Z,   FW_AIN_ACC,    FW_AIN_ACC + 1,
                                FW_AIN_ACC + 2, FW_AIN_MAG,   FW_AIN_MAG + 1, FW_AIN_MAG + 2 };
static const uint8_t mag[6] = { TLC2543_CH_X, TLC2543_CH_Y,   TLC2543_CH_Z,
                                FW_AIN_MAG,   FW_AIN_MAG + 1, FW_AIN_MAG + 2 };
static const uint8_t *const lists[2] = { all, mag }; /* [1]: a group without the accelerometer */
/* A group's codes (native words), encoded into its records in place. */
static uint16_t __idata group[9];
static uint8_t __idata group_n; /* records in the group being taken: 1..3 */

/* Whether sample seq carries the accelerometer's / magnetometer's record (1 or 0). */
#if FW_ACC_EVERY != 0
#define ACC_DUE() (uint8_t)(((uint8_t)seq & (uint8_t)(FW_ACC_EVERY - 1)) == 0u)
#else
#define ACC_DUE() 0u
#endif
#if FW_MAG_EVERY != 0
#define MAG_DUE() (uint8_t)(((uint8_t)seq & (uint8_t)(FW_MAG_EVERY - 1)) == 0u)
#else
#define MAG_DUE() 0u
#endif

/* FW_MAG_SR (config.h): the magnetometer's set/reset strap driver (docs/firmware.md, wiring):
 * P3.4's rising edge fires a set pulse, its falling edge a reset pulse
 * (free here: Timer 0 counts machine cycles, not its T0 input). A
 * magnetometer sample is converted once after each: the bridge's offset is
 * the same in both states, the field's sign flips, so
 * (c_set + 4095 - c_reset) / 2 keeps the field and drops the offset. */
#if FW_MAG_SR
#define SR_PIN P3_4
#if FW_MAG_EVERY == 1
#define IF_MAG(due) /* every sample carries the magnetometer */
#else
#define IF_MAG(due) if (due)
#endif
#if FW_MAG_EVERY != 0
static const uint8_t mag_in[3] = { FW_AIN_MAG, FW_AIN_MAG + 1, FW_AIN_MAG + 2 };
static uint16_t __idata mag_reset[3]; /* the reset state's codes */

/* The group's magnetometer codes (its last three words, converted in the
 * set state) combined with the reset state's; the scan's status. */
static int mag_flip(void)
{
    uint8_t i;
    int st;
    uint16_t __data *w = (uint16_t __data *)(group + 3u * (uint8_t)(group_n - 1u));
    SR_PIN = 0; /* reset pulse */
    st = tlc2543_scan(&adc, mag_in, 3, (uint16_t __data *)mag_reset, TLC2543_POWER_DOWN);
    for (i = 0; i < 3u; i++) {
        w[i] = (uint16_t)((uint16_t)(w[i] + 4095u - mag_reset[i]) >> 1);
    }
    return st;
}
#endif
#endif /* FW_MAG_SR */

#if FW_GYRO_OVERSAMPLE > 1
/* Gyro oversampling (config.h FW_GYRO_OVERSAMPLE = N): the sampling clock ticks N times
 * per sample period; sub-scans 0..N-2 convert the gyros alone and sum them here, the last
 * one is the group's scan (aided_sample), which adds these sums to its gyro codes. */
#define FW_SUB_TICKS (FW_PERIOD_TICKS / FW_GYRO_OVERSAMPLE)
static uint16_t __idata gsum[3]; /* the gyros' codes of sub-scans 0..fw_sub-1, summed */
uint8_t fw_sub;                  /* the sub-scan due next: 0..N-1 (not static: the
                                    simulation's device model reads it, as fw_ticks) */
static int8_t sub_st;            /* ATT_OK, or a failed sub-scan's status (the sample's ADC_ERROR) */

/* Sub-scan fw_sub (< N - 1) of sample seq: the gyros into gsum (the first) or added to it
 * (through group, free between groups). */
static void gyro_sub_scan(void)
{
    uint8_t i;
    int st;
    LINK_RX();
    FW_HOOK_SCAN_BEGIN();
    st = tlc2543_scan(&adc, all, 3, (uint16_t __data *)(fw_sub ? group : gsum), TLC2543_POWER_DOWN);
    FW_HOOK_SCAN_END();
    LINK_RX();
    if (fw_sub == 0u) {
        sub_st = ATT_OK;
    } else {
        for (i = 0; i < 3u; i++) {
            gsum[i] += group[i];
        }
    }
    if (st != ATT_OK) {
        sub_st = (int8_t)st;
    }
    fw_sub++;
}

/* The group's codes (its group_n records) as sums of N conversions: the gyros' sub-scans
 * added, the accelerometer's and magnetometer's single codes times N; with FW_GYRO_MEAN the
 * gyros' rounded mean codes instead, the others as they are (a plain stream). */
static void group_sums(void)
{
    uint8_t i;
    for (i = 0; i < 3u; i++) {
#if FW_GYRO_MEAN
        /* N a power of two: the division is a shift */
        group[i] = (uint16_t)((uint16_t)(group[i] + gsum[i] + FW_GYRO_OVERSAMPLE / 2) / FW_GYRO_OVERSAMPLE);
#else
        group[i] += gsum[i];
#endif
    }
#if !FW_GYRO_MEAN
    for (i = 3; i < (uint8_t)(3u * group_n); i++) {
        group[i] *= (uint16_t)FW_GYRO_OVERSAMPLE; /* a power of two: a shift */
    }
#endif
}
#endif /* FW_GYRO_OVERSAMPLE > 1 */
#if FW_GYRO_OVERSAMPLE > 1 && !FW_GYRO_MEAN
#define ENCODE(w) \
    att_block_encode_sums((uint8_t __data *)(w), (const uint16_t __data *)(w), FW_GYRO_OVERSAMPLE)
#else
#define ENCODE(w) att_block_encode_sample((uint8_t __data *)(w), (const uint16_t __data *)(w))
#endif

/* Scan the group of sample seq and queue its records in order (gyro,
 * accelerometer, magnetometer), or one ADC_ERROR report in their place
 * when the scan (or the encoding of a code) failed: the group goes into
 * the ring whole or not at all. A ring without room for the whole group
 * loses the sample (OVERRUN later, as for a gyro sample). */
static void aided_sample(void)
{
    int st;
    uint8_t i;
    uint8_t acc = ACC_DUE();
    uint8_t mag = MAG_DUE();
    group_n = (uint8_t)(1u + acc + mag);
    if (ovr_count != 0u) {
        flush_overrun();
    }
    if (ovr_count != 0u || att_link2_sender_room(&tx) < group_n) {
        ovr_count++;
        return;
    }
    LINK_RX();
#if FW_MAG_SR && FW_MAG_EVERY != 0
    IF_MAG(mag)
    {
        SR_PIN = 1; /* set pulse: the magnetometer is converted last in the scan */
    }
#endif
    FW_HOOK_SCAN_BEGIN();
    st = tlc2543_scan(&adc, lists[acc ^ 1u], (uint8_t)(3u * group_n), (uint16_t __data *)group,
                      TLC2543_POWER_DOWN);
#if FW_MAG_SR && FW_MAG_EVERY != 0
    IF_MAG(mag)
    {
        if (st == ATT_OK) {
            st = mag_flip();
        }
    }
#endif
    FW_HOOK_SCAN_END();
    LINK_RX();
#if FW_GYRO_OVERSAMPLE > 1
    group_sums();
    if (st == ATT_OK) {
        st = sub_st;
    }
#endif
    for (i = 0; i < group_n && st == ATT_OK; i++) {
        st = ENCODE(group + 3u * i);
    }
    if (st != ATT_OK) {
        (void)att_block_encode_adc_error((uint8_t __data *)group, seq, (int8_t)st);
        group_n = 1;
    }
    for (i = 0; i < group_n; i++) {
        (void)att_link2_sender_push(&tx, (const uint8_t __data *)(group + 3u * i));
    }
}
#endif /* FW_AIDED */

/* main's state is static: no local lives across a call, so main pushes
 * nothing on the stack around the deep calls (the scan). */
static uint16_t next_sample; /* tick of the next sample (or self-test retry) */
static __bit sampling;       /* the self-test passed */

void main(void)
{
    int st;

    P1 = 0xFD; /* P1.1 (I/O CLOCK) low; CS high; EOC, DATA OUT released */
#if FW_MAG_SR
    SR_PIN = 0; /* a reset pulse (the latch comes up high): the first sample's set pulse is an edge */
#endif
    timer0_init();
    uart_init();
    FW_HOOK_INIT();
#if FW_LINK_V2
    att_link2_sender_init(&tx, 0, 0); /* configuration: ATT_LINK2_ONE_* (config.h) */
#else
    (void)att_link_sender_init(&tx, &link_cfg);
#endif
    (void)tlc2543_init(&adc, 0, 0); /* 12-bit, MSB first, unipolar */
    (void)q_push();                 /* the queue is empty: BOOT report first */
    (void)att_block_encode_boot(
        wp, (uint16_t)(FW_PERIOD_TICKS | (FW_LINK_V2 ? ATT_BLOCK_BOOT_LINK2 : 0)),
        (uint8_t)(FW_BAUD / (long)ATT_BLOCK_BAUD_UNIT)); /* the protocol in the period word */
    q_commit();
#if FW_AIDED
#if FW_GYRO_OVERSAMPLE > 1 && !FW_GYRO_MEAN
    (void)q_push(); /* OVERSAMPLE right after BOOT: the sample words are sums of N */
    (void)att_block_encode_oversample(wp, (uint8_t)FW_GYRO_OVERSAMPLE);
    q_commit();
#endif
    (void)q_push(); /* CHANNELS right after BOOT: the board and its stream */
    (void)att_block_encode_channels(wp, (uint8_t)ATT_BLOCK_BOARD_AIDED9, (uint8_t)FW_CHANNELS,
                                    (uint8_t)FW_ACC_EVERY, (uint8_t)FW_MAG_EVERY);
    q_commit();
#endif
    sampling = 0;
    next_sample = tick_now();

    for (;;) {
        (void)tick_now(); /* fw_ticks = now */
        FW_HOOK_LOOP_START();

#if FW_LINK_V2
        /* 1. a byte from the receiver (an ACK frees ring slots) */
        LINK_RX();

        /* 2. the transmitter is free: the sender's next byte, if any */
        if (TX_FREE) {
            FW_HOOK_POLL_BEGIN();
            st = att_link2_sender_poll(&tx, fw_ticks, &txb);
            FW_HOOK_POLL(st);
            if (st == ATT_LINK2_SEND) {
                TX_FREE = 0;
                SBUF = txb;
                FW_HOOK_TX();
            } else if (st < 0) {
                att_link2_sender_reset(&tx); /* corrupted state: new session */
            }
        }
#else
        /* 1. a byte from the receiver */
        if (RI) {
            RI = 0;
            FW_HOOK_RX(SBUF);
            if (att_link_sender_sink(&tx, SBUF, fw_ticks) == ATT_LINK_ACCEPTED) {
                block_accepted();
            }
        }

        /* 2. the transmitter is free: what does the sender want? */
        if (TI) {
            st = att_link_sender_poll(&tx, fw_ticks, &txb);
            FW_HOOK_POLL(st);
            if (st == ATT_LINK_SEND) {
                TI = 0;
                SBUF = txb;
                FW_HOOK_TX();
            } else if (st == ATT_LINK_IDLE) {
                if (q_any) {
                    (void)att_link_sender_start(&tx, queue[q_head], fw_ticks);
                    FW_HOOK_BLOCK_START();
                }
            } else if (st == ATT_LINK_GAVE_UP) {
                block_given_up();
            } else if (st < 0) {
                att_link_sender_reset(&tx); /* corrupted state: resend the head block */
            }
        }
#endif
        FW_HOOK_LOOP_END();

        /* 3. the sampling clock (or the self-test retry clock) */
        if (ovr_count != 0u) {
            flush_overrun();
        }
        if ((int16_t)(fw_ticks - next_sample) >= 0) {
            if (sampling) {
#if FW_AIDED && FW_GYRO_OVERSAMPLE > 1
                next_sample += (uint16_t)FW_SUB_TICKS;
                if (fw_sub != (uint8_t)(FW_GYRO_OVERSAMPLE - 1)) {
                    gyro_sub_scan();
                    continue; /* the same sample: seq stays */
                }
                aided_sample(); /* the last sub-scan (fw_sub = N - 1): the group */
                fw_sub = 0;
#elif FW_AIDED
                next_sample += (uint16_t)FW_PERIOD_TICKS;
                aided_sample();
#else
                next_sample += (uint16_t)FW_PERIOD_TICKS;
                if (sample_slot()) {
                    LINK_RX(); /* v2: the byte that came during the poll, before the scan's 0.9 ms */
                    FW_HOOK_SCAN_BEGIN();
                    st = tlc2543_scan(&adc, xyz, 3, (uint16_t __data *)wp, TLC2543_POWER_DOWN);
                    FW_HOOK_SCAN_END();
                    LINK_RX(); /* v2: the byte that came during the scan */
                    sample_store(st);
                }
#endif
                seq++;
            } else {
                if (q_push()) { /* the report slot, also where the codes land */
                    seq++;      /* until sampling starts, seq counts the self-test attempts */
                    st = tlc2543_self_test_codes(&adc, (uint16_t __data *)wp);
                    FW_HOOK_SELFTEST_END();
                    if (self_test_done(st)) {
                        sampling = 1;
                        seq = 0;
                        next_sample = fw_ticks;
                        continue;
                    }
                }
                next_sample = (uint16_t)(fw_ticks + FW_SELFTEST_RETRY_TICKS);
            }
        }
    }
}
