/*
 * libattitude — link sender A (see attitude/link.h and docs/link.md).
 *
 * Portable C99 that SDCC compiles for the AT89S51 (small model): 8/16-bit
 * arithmetic, no float, no function pointers, no library calls.
 */
#include "attitude/link.h"

/* Private states. */
typedef enum {
    SS_IDLE = 0,         /* no block */
    SS_SEND_SYN,         /* next poll hands out 0xAA */
    SS_WAIT_SYN_ACK,     /* waiting for 0xBB (syn timer running) */
    SS_SEND_DATA,        /* next poll hands out block[index] */
    SS_SEND_CHECKSUM,    /* next poll hands out the checksum */
    SS_WAIT_ANSWER,      /* waiting for 0x00 / 0xFF (answer timer running) */
    SS_TIMED_OUT,        /* a sink found the timer expired: next poll reports it */
    SS_GAVE_UP,          /* next poll reports the give-up */
    SS_COUNT
} ss_state;

uint8_t att_link_checksum(const uint8_t *data, uint8_t n)
{
    uint8_t sum = 0;
    if (data == NULL) {
        return 0;
    }
    while (n != 0) {
        sum = (uint8_t)(sum + *data);
        ++data;
        --n;
    }
    return sum;
}

void att_link_sender_config_init(att_link_sender_config *cfg, uint8_t block_size)
{
    if (cfg == NULL) {
        return;
    }
    cfg->syn_timeout = 50;    /* ms: 0xAA + 0xBB on the wire (2 x 1.04 ms) + B's latency */
    cfg->answer_timeout = 50; /* ms: checksum + answer on the wire + B's latency */
    cfg->block_size = block_size;
    cfg->max_attempts = 5;
}

static uint8_t timeout_ok(uint16_t t)
{
    return (uint8_t)(t >= 1u && t <= (uint16_t)ATT_LINK_TIMEOUT_MAX);
}

int att_link_sender_init(att_link_sender ATT_LINK_MEM *s, const att_link_sender_config *cfg)
{
    if (s == NULL || cfg == NULL) {
        return ATT_LINK_E_NULL;
    }
    if (cfg->block_size < (uint8_t)ATT_LINK_BLOCK_MIN || cfg->block_size > (uint8_t)ATT_LINK_BLOCK_MAX
        || cfg->max_attempts == 0 || !timeout_ok(cfg->syn_timeout) || !timeout_ok(cfg->answer_timeout)) {
        return ATT_LINK_E_CONFIG;
    }
    s->cfg = *cfg;
    s->stats.blocks_sent = 0;
    s->stats.blocks_accepted = 0;
    s->stats.naks = 0;
    s->stats.timeouts = 0;
    s->stats.gave_up = 0;
    s->stats.bytes_discarded = 0;
    att_link_sender_reset(s);
    return ATT_OK;
}

void att_link_sender_reset(att_link_sender ATT_LINK_MEM *s)
{
    if (s == NULL) {
        return;
    }
    s->block = NULL;
    s->t0 = 0;
    s->state = (uint8_t)SS_IDLE;
    s->index = 0;
    s->attempts = 0;
}

int att_link_sender_start(att_link_sender ATT_LINK_MEM *s, const uint8_t ATT_LINK_MEM *block, uint16_t tick)
{
    if (s == NULL || block == NULL) {
        return ATT_LINK_E_NULL;
    }
    if (s->state != (uint8_t)SS_IDLE) {
        return ATT_LINK_E_BUSY;
    }
    s->block = block;
    s->attempts = 0;
    s->index = 0;
    s->t0 = tick;
    s->state = (uint8_t)SS_SEND_SYN;
    return ATT_OK;
}

/* The state after an attempt failed (NAK or timeout). */
static uint8_t after_failed_attempt(const att_link_sender ATT_LINK_MEM *s)
{
    return (uint8_t)(s->attempts < s->cfg.max_attempts ? SS_SEND_SYN : SS_GAVE_UP);
}

/* Has the running timer (started at t0) expired at `tick`? */
static uint8_t timer_expired(const att_link_sender ATT_LINK_MEM *s, uint16_t tick)
{
    uint16_t limit = s->state == (uint8_t)SS_WAIT_SYN_ACK ? s->cfg.syn_timeout : s->cfg.answer_timeout;
    return (uint8_t)((uint16_t)(tick - s->t0) > limit);
}

static uint8_t waiting(const att_link_sender ATT_LINK_MEM *s)
{
    return (uint8_t)(s->state == (uint8_t)SS_WAIT_SYN_ACK || s->state == (uint8_t)SS_WAIT_ANSWER);
}

/* -- sink: one function per state that takes bytes ------------------- */

static att_link_result sink_wait_syn_ack(att_link_sender ATT_LINK_MEM *s, uint8_t byte)
{
    if (byte != (uint8_t)ATT_LINK_SYN_ACK) {
        s->stats.bytes_discarded++;
        return ATT_LINK_DISCARDED;
    }
    s->index = 0;
    s->state = (uint8_t)SS_SEND_DATA;
    return ATT_LINK_SYN_RX;
}

static att_link_result sink_wait_answer(att_link_sender ATT_LINK_MEM *s, uint8_t byte)
{
    if (byte == (uint8_t)ATT_LINK_ACK) {
        s->stats.blocks_accepted++;
        s->block = NULL;
        s->state = (uint8_t)SS_IDLE;
        return ATT_LINK_ACCEPTED;
    }
    if (byte == (uint8_t)ATT_LINK_NAK) {
        s->stats.naks++;
        s->state = after_failed_attempt(s);
        return ATT_LINK_REJECTED;
    }
    s->stats.bytes_discarded++; /* a corrupted answer: keep waiting for the timer */
    return ATT_LINK_DISCARDED;
}

att_link_result att_link_sender_sink(att_link_sender ATT_LINK_MEM *s, uint8_t byte, uint16_t tick)
{
    if (s == NULL) {
        return ATT_LINK_E_NULL;
    }
    if (s->state >= (uint8_t)SS_COUNT) {
        return ATT_LINK_E_STATE;
    }
    if (waiting(s) && timer_expired(s, tick)) {
        s->stats.timeouts++;
        s->state = (uint8_t)SS_TIMED_OUT;
    }
    switch (s->state) {
    case SS_WAIT_SYN_ACK:
        return sink_wait_syn_ack(s, byte);
    case SS_WAIT_ANSWER:
        return sink_wait_answer(s, byte);
    default:
        s->stats.bytes_discarded++;
        return ATT_LINK_DISCARDED;
    }
}

/* -- poll: one function per state ------------------------------------ */

static att_link_result poll_send_syn(att_link_sender ATT_LINK_MEM *s, uint16_t tick, uint8_t ATT_LINK_MEM *out)
{
    s->attempts++;
    s->t0 = tick;
    s->state = (uint8_t)SS_WAIT_SYN_ACK;
    *out = (uint8_t)ATT_LINK_SYN;
    return ATT_LINK_SEND;
}

static att_link_result poll_waiting(att_link_sender ATT_LINK_MEM *s, uint16_t tick)
{
    if (!timer_expired(s, tick)) {
        return ATT_LINK_NONE;
    }
    s->stats.timeouts++;
    s->state = after_failed_attempt(s);
    return ATT_LINK_TIMEOUT;
}

static att_link_result poll_send_data(att_link_sender ATT_LINK_MEM *s, uint8_t ATT_LINK_MEM *out)
{
    *out = s->block[s->index];
    s->index++;
    if (s->index >= s->cfg.block_size) {
        s->state = (uint8_t)SS_SEND_CHECKSUM;
    }
    return ATT_LINK_SEND;
}

static att_link_result poll_send_checksum(att_link_sender ATT_LINK_MEM *s, uint16_t tick, uint8_t ATT_LINK_MEM *out)
{
    uint8_t i;
    uint8_t sum = 0;
    for (i = 0; i < s->cfg.block_size; i++) {
        sum = (uint8_t)(sum + s->block[i]);
    }
    *out = sum;
    s->stats.blocks_sent++;
    s->t0 = tick;
    s->state = (uint8_t)SS_WAIT_ANSWER;
    return ATT_LINK_SEND;
}

static att_link_result poll_timed_out(att_link_sender ATT_LINK_MEM *s)
{
    s->state = after_failed_attempt(s);
    return ATT_LINK_TIMEOUT;
}

static att_link_result poll_gave_up(att_link_sender ATT_LINK_MEM *s)
{
    s->stats.gave_up++;
    s->block = NULL;
    s->state = (uint8_t)SS_IDLE;
    return ATT_LINK_GAVE_UP;
}

att_link_result att_link_sender_poll(att_link_sender ATT_LINK_MEM *s, uint16_t tick, uint8_t ATT_LINK_MEM *out_byte)
{
    if (s == NULL || out_byte == NULL) {
        return ATT_LINK_E_NULL;
    }
    switch (s->state) {
    case SS_IDLE:
        return ATT_LINK_IDLE;
    case SS_SEND_SYN:
        return poll_send_syn(s, tick, out_byte);
    case SS_WAIT_SYN_ACK:
    case SS_WAIT_ANSWER:
        return poll_waiting(s, tick);
    case SS_SEND_DATA:
        return poll_send_data(s, out_byte);
    case SS_SEND_CHECKSUM:
        return poll_send_checksum(s, tick, out_byte);
    case SS_TIMED_OUT:
        return poll_timed_out(s);
    case SS_GAVE_UP:
        return poll_gave_up(s);
    default:
        return ATT_LINK_E_STATE;
    }
}

uint16_t att_link_sender_ticks_left(const att_link_sender ATT_LINK_MEM *s, uint16_t now)
{
    uint16_t elapsed;
    uint16_t limit;
    if (s == NULL) {
        return (uint16_t)ATT_LINK_NO_TIMER;
    }
    if (s->state == (uint8_t)SS_IDLE || s->state >= (uint8_t)SS_COUNT) {
        return (uint16_t)ATT_LINK_NO_TIMER;
    }
    if (!waiting(s)) {
        return 0; /* something to hand out or report now */
    }
    elapsed = (uint16_t)(now - s->t0);
    limit = s->state == (uint8_t)SS_WAIT_SYN_ACK ? s->cfg.syn_timeout : s->cfg.answer_timeout;
    if (elapsed > limit) {
        return 0;
    }
    return (uint16_t)(limit - elapsed + 1u);
}
