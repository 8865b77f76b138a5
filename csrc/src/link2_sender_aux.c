/*
 * libattitude — link v2 sender helpers a firmware can do without
 * (attitude/link2.h): defaults, the timer query, the CRC of a buffer.
 * Kept out of link2_sender.c because SDCC links whole modules.
 */
#include "attitude/link2.h"

#include "link2_private.h"

void att_link2_sender_config_init(att_link2_sender_config *cfg, uint8_t ring_size)
{
    if (cfg == NULL) {
        return;
    }
    cfg->rto = 200;
    cfg->max_samples = (uint8_t)ATT_LINK2_SAMPLES_DEFAULT;
    cfg->ring_size = ring_size;
}

/* Does B's limit let A send record `seq`? (limit - seq in 1..127) */
static uint8_t open_for(const att_link2_sender *s, uint8_t seq)
{
    return (uint8_t)((uint8_t)((uint8_t)(s->limit - seq) - 1u) < (uint8_t)ATT_LINK2_WINDOW_MAX);
}

uint16_t att_link2_sender_ticks_left(const att_link2_sender *s, uint16_t now)
{
    uint16_t elapsed;
    if (s == NULL || s->session >= (uint8_t)SES_BAD) {
        return (uint16_t)ATT_LINK2_NO_TIMER;
    }
    if (s->tx != (uint8_t)TX_IDLE || s->session == (uint8_t)SES_SYN_SEND
        || (s->session == (uint8_t)SES_RUN && s->next != s->head && open_for(s, s->next))) {
        return 0; /* a byte to send now */
    }
    if (s->session != (uint8_t)SES_SYN_WAIT && s->hi == s->base && s->next == s->head) {
        return (uint16_t)ATT_LINK2_NO_TIMER; /* nothing awaited */
    }
    elapsed = (uint16_t)(now - s->t0);
    return elapsed > s->cfg.rto ? 0u : (uint16_t)(s->cfg.rto - elapsed + 1u);
}

uint32_t att_link2_crc(const uint8_t *data, uint16_t n)
{
    uint32_t crc = 0xFFFFFFFFul;
    uint16_t i;
    if (data == NULL) {
        return 0;
    }
    for (i = 0; i < n; i++) {
        crc = att_link2_crc_byte(crc, data[i]);
    }
    return crc ^ 0xFFFFFFFFul;
}
