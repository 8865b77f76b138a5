/*
 * libattitude — link receiver B (see attitude/link.h and docs/link.md).
 *
 * The sender's style (link_sender.c): one function per state, and what
 * poll must report next is a state of its own, not a set of flag bits.
 * Two small machines share the struct:
 *
 *   state    what sink does with the next byte: IDLE (hunting for 0xAA),
 *            HUNT (the same, after bytes were discarded since the last
 *            handshake: the next 0xAA is a resync), DATA, CHECKSUM;
 *   pending  what the next poll reports: nothing, a byte to hand out
 *            (0xBB, 0x00, 0xFF), or first the timeout of a partial block a
 *            sink dropped and then that byte. A sink may queue a report
 *            before the previous one was polled (a caller that sinks
 *            several bytes between polls): a new byte replaces a queued one,
 *            a timeout stays queued in front of it, and dropping a partial
 *            block voids a 0xBB not handed out yet.
 */
#include "attitude/link.h"

/* Receive states (what sink does with a byte). */
typedef enum {
    RS_IDLE = 0, /* hunting for 0xAA */
    RS_HUNT,     /* hunting for 0xAA, bytes discarded since the last handshake */
    RS_DATA,     /* storing data bytes (index < N) */
    RS_CHECKSUM, /* all N data bytes in, next byte is the checksum */
    RS_COUNT
} rs_state;

/* Pending states (what the next poll reports): a byte to hand out, and a
 * dropped partial block's timeout to report before it. */
typedef enum {
    RP_NONE = 0,        /* nothing: poll reports NONE (in a block) or IDLE */
    RP_SYN_ACK,         /* hand out 0xBB; the gap timer starts */
    RP_ACK,             /* hand out 0x00 */
    RP_NAK,             /* hand out 0xFF */
    RP_TIMEOUT,         /* report TIMEOUT (a sink dropped a partial block) */
    RP_TIMEOUT_SYN_ACK, /* report TIMEOUT, then RP_SYN_ACK */
    RP_TIMEOUT_ACK,     /* report TIMEOUT, then RP_ACK */
    RP_TIMEOUT_NAK,     /* report TIMEOUT, then RP_NAK */
    RP_COUNT
} rp_pending;

enum {
    RP_TIMEOUT_FIRST = RP_TIMEOUT - RP_NONE /* RP_TIMEOUT_x = RP_x + this (x: a byte or none) */
};

void att_link_receiver_config_init(att_link_receiver_config *cfg, uint8_t block_size)
{
    if (cfg == NULL) {
        return;
    }
    cfg->gap_timeout = 20; /* ms: bytes of a block are back to back (1.04 ms); allows B's
                              scheduling jitter, and stays below A's 50 ms timeouts */
    cfg->block_size = block_size;
}

int att_link_receiver_init(att_link_receiver *r, const att_link_receiver_config *cfg, uint8_t *block)
{
    if (r == NULL || cfg == NULL || block == NULL) {
        return ATT_LINK_E_NULL;
    }
    if (cfg->block_size < (uint8_t)ATT_LINK_BLOCK_MIN || cfg->block_size > (uint8_t)ATT_LINK_BLOCK_MAX
        || cfg->gap_timeout < 1u || cfg->gap_timeout > (uint16_t)ATT_LINK_TIMEOUT_MAX) {
        return ATT_LINK_E_CONFIG;
    }
    r->cfg = *cfg;
    r->block = block;
    r->stats.syns = 0;
    r->stats.blocks_accepted = 0;
    r->stats.naks = 0;
    r->stats.timeouts = 0;
    r->stats.resyncs = 0;
    r->stats.bytes_discarded = 0;
    att_link_receiver_reset(r);
    return ATT_OK;
}

void att_link_receiver_reset(att_link_receiver *r)
{
    if (r == NULL) {
        return;
    }
    r->t_last = 0;
    r->state = (uint8_t)RS_IDLE;
    r->pending = (uint8_t)RP_NONE;
    r->index = 0;
    r->sum = 0;
}

/* -- pending states ---------------------------------------------------- */

/* The byte part of a pending state (RP_NONE, RP_SYN_ACK, RP_ACK or RP_NAK). */
static uint8_t pending_byte(uint8_t p)
{
    return (uint8_t)(p >= (uint8_t)RP_TIMEOUT ? p - (uint8_t)RP_TIMEOUT_FIRST : p);
}

/* Queue the byte b (RP_SYN_ACK, RP_ACK, RP_NAK) after a queued timeout, replacing a queued byte. */
static void queue_byte(att_link_receiver *r, uint8_t b)
{
    r->pending = (uint8_t)(r->pending >= (uint8_t)RP_TIMEOUT ? b + (uint8_t)RP_TIMEOUT_FIRST : b);
}

/* -- the gap timer ------------------------------------------------------- */

static uint8_t in_block(const att_link_receiver *r)
{
    return (uint8_t)(r->state == (uint8_t)RS_DATA || r->state == (uint8_t)RS_CHECKSUM);
}

static uint8_t gap_expired(const att_link_receiver *r, uint16_t tick)
{
    return (uint8_t)((uint16_t)(tick - r->t_last) > r->cfg.gap_timeout);
}

/* Drop the partial block after a gap; back to idle. A 0xBB not handed out yet is void now. */
static void drop_partial(att_link_receiver *r)
{
    uint8_t b = pending_byte(r->pending);
    r->stats.timeouts++;
    r->stats.bytes_discarded += r->index;
    r->index = 0;
    r->sum = 0;
    r->state = (uint8_t)RS_IDLE;
    if (b == (uint8_t)RP_SYN_ACK) {
        r->pending = (uint8_t)(r->pending - b + (uint8_t)RP_NONE);
    }
}

/* -- sink: one function per state ------------------------------------ */

static att_link_result sink_idle(att_link_receiver *r, uint8_t byte, uint16_t tick)
{
    if (byte != (uint8_t)ATT_LINK_SYN) {
        r->stats.bytes_discarded++;
        r->state = (uint8_t)RS_HUNT;
        return ATT_LINK_DISCARDED;
    }
    r->stats.syns++;
    if (r->state == (uint8_t)RS_HUNT) {
        r->stats.resyncs++;
    }
    r->index = 0;
    r->sum = 0;
    r->t_last = tick;
    r->state = (uint8_t)RS_DATA;
    queue_byte(r, (uint8_t)RP_SYN_ACK);
    return ATT_LINK_SYN_RX;
}

static att_link_result sink_data(att_link_receiver *r, uint8_t byte, uint16_t tick)
{
    r->block[r->index] = byte;
    r->index++;
    r->sum = (uint8_t)(r->sum + byte);
    r->t_last = tick;
    if (r->index >= r->cfg.block_size) {
        r->state = (uint8_t)RS_CHECKSUM;
    }
    return ATT_LINK_DATA_RX;
}

static att_link_result sink_checksum(att_link_receiver *r, uint8_t byte)
{
    uint8_t ok = (uint8_t)(byte == r->sum);
    r->index = 0;
    r->sum = 0;
    r->state = (uint8_t)RS_IDLE;
    if (ok) {
        r->stats.blocks_accepted++;
        queue_byte(r, (uint8_t)RP_ACK);
        return ATT_LINK_ACCEPTED;
    }
    r->stats.naks++;
    queue_byte(r, (uint8_t)RP_NAK);
    return ATT_LINK_REJECTED;
}

static uint8_t corrupted(const att_link_receiver *r)
{
    return (uint8_t)(r->state >= (uint8_t)RS_COUNT || r->pending >= (uint8_t)RP_COUNT
                     || r->index > r->cfg.block_size || r->cfg.block_size > (uint8_t)ATT_LINK_BLOCK_MAX);
}

att_link_result att_link_receiver_sink(att_link_receiver *r, uint8_t byte, uint16_t tick)
{
    if (r == NULL || r->block == NULL) {
        return ATT_LINK_E_NULL;
    }
    if (corrupted(r)) {
        return ATT_LINK_E_STATE;
    }
    if (in_block(r) && gap_expired(r, tick)) { /* dropped first, reported by the next poll */
        drop_partial(r);
        if (r->pending < (uint8_t)RP_TIMEOUT) { /* one report for the drops since the last poll */
            r->pending = (uint8_t)(r->pending + (uint8_t)RP_TIMEOUT_FIRST);
        }
    }
    switch (r->state) {
    case RS_IDLE:
    case RS_HUNT:
        return sink_idle(r, byte, tick);
    case RS_DATA:
        return sink_data(r, byte, tick);
    default: /* RS_CHECKSUM */
        return sink_checksum(r, byte);
    }
}

/* -- poll: one function per pending state --------------------------- */

static att_link_result poll_none(const att_link_receiver *r)
{
    return (r->state == (uint8_t)RS_IDLE || r->state == (uint8_t)RS_HUNT) ? ATT_LINK_IDLE : ATT_LINK_NONE;
}

static att_link_result poll_send(att_link_receiver *r, uint16_t tick, uint8_t *out_byte)
{
    uint8_t p = r->pending;
    if (p == (uint8_t)RP_SYN_ACK) {
        *out_byte = (uint8_t)ATT_LINK_SYN_ACK;
        if (r->state == (uint8_t)RS_DATA && r->index == 0u) {
            r->t_last = tick; /* the gap timer counts from 0xBB leaving */
        }
    } else {
        *out_byte = (uint8_t)(p == (uint8_t)RP_ACK ? ATT_LINK_ACK : ATT_LINK_NAK);
    }
    r->pending = (uint8_t)RP_NONE;
    return ATT_LINK_SEND;
}

static att_link_result poll_timeout(att_link_receiver *r)
{
    r->pending = pending_byte(r->pending); /* the byte queued behind it, if any, comes next */
    return ATT_LINK_TIMEOUT;
}

att_link_result att_link_receiver_poll(att_link_receiver *r, uint16_t tick, uint8_t *out_byte)
{
    if (r == NULL || out_byte == NULL) {
        return ATT_LINK_E_NULL;
    }
    if (r->state >= (uint8_t)RS_COUNT || r->pending >= (uint8_t)RP_COUNT) {
        return ATT_LINK_E_STATE;
    }
    if (in_block(r) && gap_expired(r, tick)) { /* found by this poll: reported now */
        drop_partial(r);
        return ATT_LINK_TIMEOUT;
    }
    switch (r->pending) {
    case RP_NONE:
        return poll_none(r);
    case RP_SYN_ACK:
    case RP_ACK:
    case RP_NAK:
        return poll_send(r, tick, out_byte);
    default: /* RP_TIMEOUT... */
        return poll_timeout(r);
    }
}

uint16_t att_link_receiver_ticks_left(const att_link_receiver *r, uint16_t now)
{
    uint16_t elapsed;
    if (r == NULL || r->state >= (uint8_t)RS_COUNT) {
        return (uint16_t)ATT_LINK_NO_TIMER;
    }
    if (r->pending != (uint8_t)RP_NONE) {
        return 0;
    }
    if (!in_block(r)) {
        return (uint16_t)ATT_LINK_NO_TIMER;
    }
    elapsed = (uint16_t)(now - r->t_last);
    if (elapsed > r->cfg.gap_timeout) {
        return 0;
    }
    return (uint16_t)(r->cfg.gap_timeout - elapsed + 1u);
}
