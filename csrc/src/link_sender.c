/*
 * libattitude — link sender A (see attitude/link.h and docs/link.md).
 *
 * Portable C99 that SDCC compiles for the AT89S51 (small model): 8/16-bit
 * arithmetic, no float, no function pointers, no library calls. This file
 * holds only what a firmware needs (init, reset, start, sink, poll); the
 * helpers it can do without are in link_sender_aux.c, because SDCC links
 * whole modules and the AT89S51 has 4 KB of flash.
 */
#include "attitude/link.h"

#include "link_sender_state.h"

/* 1..ATT_LINK_TIMEOUT_MAX, in one unsigned comparison (0 wraps to 0xFFFF); the block
 * size check below uses the same trick (ATT_LINK_BLOCK_MIN is 1). */
#define TIMEOUT_BAD(t) ((uint16_t)((t)-1u) > (uint16_t)(ATT_LINK_TIMEOUT_MAX - 1))

int att_link_sender_init(att_link_sender ATT_LINK_MEM *s, const att_link_sender_config *cfg)
{
    uint8_t ATT_LINK_MEM *p;
    uint8_t n;
    if (s == NULL || cfg == NULL) {
        return ATT_LINK_E_NULL;
    }
    s->cfg = *cfg; /* checked in place: cheaper than through a generic pointer on the 8051 */
    p = (uint8_t ATT_LINK_MEM *)&s->stats;
    n = (uint8_t)sizeof(s->stats);
    do {
        *p++ = 0;
    } while (--n != 0);
    att_link_sender_reset(s);
    if ((uint8_t)(s->cfg.block_size - 1u) > (uint8_t)(ATT_LINK_BLOCK_MAX - 1) || s->cfg.max_attempts == 0
        || TIMEOUT_BAD(s->cfg.syn_timeout) || TIMEOUT_BAD(s->cfg.answer_timeout)) {
        s->state = (uint8_t)SS_COUNT; /* unusable: every call reports an error */
        return ATT_LINK_E_CONFIG;
    }
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

static att_link_result poll_send_syn(att_link_sender ATT_LINK_MEM *s, uint16_t tick,
                                     uint8_t ATT_LINK_MEM *out)
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

static att_link_result poll_send_checksum(att_link_sender ATT_LINK_MEM *s, uint16_t tick,
                                          uint8_t ATT_LINK_MEM *out)
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

att_link_result att_link_sender_poll(att_link_sender ATT_LINK_MEM *s, uint16_t tick,
                                     uint8_t ATT_LINK_MEM *out_byte)
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
