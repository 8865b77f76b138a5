/*
 * libattitude — link sender A, the helpers a firmware can do without
 * (defaults, checksum of a buffer, time to the next timer event); kept
 * out of link_sender.c so that an 8051 image does not carry them.
 */
#include "attitude/link.h"
#include "link_sender_state.h"

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
    if (s->state != (uint8_t)SS_WAIT_SYN_ACK && s->state != (uint8_t)SS_WAIT_ANSWER) {
        return 0; /* something to hand out or report now */
    }
    elapsed = (uint16_t)(now - s->t0);
    limit = s->state == (uint8_t)SS_WAIT_SYN_ACK ? s->cfg.syn_timeout : s->cfg.answer_timeout;
    if (elapsed > limit) {
        return 0;
    }
    return (uint16_t)(limit - elapsed + 1u);
}
