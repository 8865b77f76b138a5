/*
 * libattitude — link receiver B (see attitude/link.h and docs/link.md).
 */
#include "attitude/link.h"

/* Private states. */
typedef enum {
    RS_IDLE = 0, /* hunting for 0xAA */
    RS_DATA,     /* storing data bytes (index < N) */
    RS_CHECKSUM, /* all N data bytes in, next byte is the checksum */
    RS_COUNT
} rs_state;

/* Private flags. */
enum {
    RF_OUT_PENDING = 0x01,     /* out_byte waits to be handed out */
    RF_TIMEOUT_PENDING = 0x02, /* a sink dropped a partial block: next poll reports it */
    RF_DISCARDED = 0x04,       /* bytes were discarded while idle since the last handshake */
    RF_OUT_IS_SYN_ACK = 0x08   /* the pending byte is 0xBB (restarts the gap timer) */
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
    r->index = 0;
    r->sum = 0;
    r->out_byte = 0;
    r->flags = 0;
}

static void queue_out(att_link_receiver *r, uint8_t byte)
{
    r->out_byte = byte;
    r->flags = (uint8_t)((r->flags & ~RF_OUT_IS_SYN_ACK) | RF_OUT_PENDING);
    if (byte == (uint8_t)ATT_LINK_SYN_ACK) {
        r->flags |= RF_OUT_IS_SYN_ACK;
    }
}

static uint8_t in_block(const att_link_receiver *r)
{
    return (uint8_t)(r->state == (uint8_t)RS_DATA || r->state == (uint8_t)RS_CHECKSUM);
}

static uint8_t gap_expired(const att_link_receiver *r, uint16_t tick)
{
    return (uint8_t)((uint16_t)(tick - r->t_last) > r->cfg.gap_timeout);
}

/* Drop the partial block after a gap; back to idle. */
static void drop_partial(att_link_receiver *r)
{
    r->stats.timeouts++;
    r->stats.bytes_discarded += r->index;
    r->index = 0;
    r->sum = 0;
    r->state = (uint8_t)RS_IDLE;
    if (r->flags & RF_OUT_IS_SYN_ACK) { /* a 0xBB not handed out yet is void now */
        r->flags &= (uint8_t) ~(RF_OUT_PENDING | RF_OUT_IS_SYN_ACK);
    }
}

/* -- sink: one function per state ------------------------------------ */

static att_link_result sink_idle(att_link_receiver *r, uint8_t byte, uint16_t tick)
{
    if (byte != (uint8_t)ATT_LINK_SYN) {
        r->stats.bytes_discarded++;
        r->flags |= RF_DISCARDED;
        return ATT_LINK_DISCARDED;
    }
    r->stats.syns++;
    if (r->flags & RF_DISCARDED) {
        r->stats.resyncs++;
        r->flags &= (uint8_t)~RF_DISCARDED;
    }
    r->index = 0;
    r->sum = 0;
    r->t_last = tick;
    r->state = (uint8_t)RS_DATA;
    queue_out(r, (uint8_t)ATT_LINK_SYN_ACK);
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
        queue_out(r, (uint8_t)ATT_LINK_ACK);
        return ATT_LINK_ACCEPTED;
    }
    r->stats.naks++;
    queue_out(r, (uint8_t)ATT_LINK_NAK);
    return ATT_LINK_REJECTED;
}

att_link_result att_link_receiver_sink(att_link_receiver *r, uint8_t byte, uint16_t tick)
{
    if (r == NULL || r->block == NULL) {
        return ATT_LINK_E_NULL;
    }
    if (r->state >= (uint8_t)RS_COUNT || r->index > r->cfg.block_size
        || r->cfg.block_size > (uint8_t)ATT_LINK_BLOCK_MAX) {
        return ATT_LINK_E_STATE;
    }
    if (in_block(r) && gap_expired(r, tick)) {
        drop_partial(r);
        r->flags |= RF_TIMEOUT_PENDING;
    }
    switch (r->state) {
    case RS_IDLE:
        return sink_idle(r, byte, tick);
    case RS_DATA:
        return sink_data(r, byte, tick);
    default: /* RS_CHECKSUM */
        return sink_checksum(r, byte);
    }
}

att_link_result att_link_receiver_poll(att_link_receiver *r, uint16_t tick, uint8_t *out_byte)
{
    if (r == NULL || out_byte == NULL) {
        return ATT_LINK_E_NULL;
    }
    if (r->state >= (uint8_t)RS_COUNT) {
        return ATT_LINK_E_STATE;
    }
    if (in_block(r) && gap_expired(r, tick)) {
        drop_partial(r);
        return ATT_LINK_TIMEOUT;
    }
    if (r->flags & RF_TIMEOUT_PENDING) {
        r->flags &= (uint8_t)~RF_TIMEOUT_PENDING;
        return ATT_LINK_TIMEOUT;
    }
    if (r->flags & RF_OUT_PENDING) {
        if ((r->flags & RF_OUT_IS_SYN_ACK) && r->state == (uint8_t)RS_DATA && r->index == 0) {
            r->t_last = tick; /* the gap timer counts from 0xBB leaving */
        }
        r->flags &= (uint8_t) ~(RF_OUT_PENDING | RF_OUT_IS_SYN_ACK);
        *out_byte = r->out_byte;
        return ATT_LINK_SEND;
    }
    return r->state == (uint8_t)RS_IDLE ? ATT_LINK_IDLE : ATT_LINK_NONE;
}

uint16_t att_link_receiver_ticks_left(const att_link_receiver *r, uint16_t now)
{
    uint16_t elapsed;
    if (r == NULL || r->state >= (uint8_t)RS_COUNT) {
        return (uint16_t)ATT_LINK_NO_TIMER;
    }
    if (r->flags & (RF_OUT_PENDING | RF_TIMEOUT_PENDING)) {
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
