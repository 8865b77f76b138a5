/*
 * libattitude host-only: link v2 end-to-end simulation (link2_sim.h).
 */
#include "link2_sim.h"

#include <string.h>

void att_link2_sim_record(uint64_t i, uint32_t report_every, uint8_t *rec)
{
    uint64_t h = (i + 1u) * 0x9E3779B97F4A7C15ull;
    uint16_t c;
    int k;
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 32;
    if (report_every != 0u && i % report_every == report_every - 1u) {
        rec[0] = 0xFE;
        rec[1] = 3; /* OVERRUN-shaped: first = i, count = hash */
        rec[2] = (uint8_t)(i >> 8);
        rec[3] = (uint8_t)i;
        rec[4] = (uint8_t)(h >> 8);
        rec[5] = (uint8_t)(h | 1u);
        return;
    }
    for (k = 0; k < 3; k++) {
        c = (uint16_t)((h >> (12 * k)) & 0x0FFFu);
        rec[2 * k] = (uint8_t)(c >> 8);
        rec[2 * k + 1] = (uint8_t)c;
    }
}

typedef struct {
    uint8_t bytes[64];
    int n;
} inbox;

/* One delivered record: compare with the expected one and its neighbours. */
static void check_record(const att_link2_sim_config *cfg, att_link2_sim_result *res, uint64_t *expect,
                         const uint8_t *got)
{
    uint8_t want[6];
    uint64_t d;
    res->delivered++;
    att_link2_sim_record(*expect, cfg->report_every, want);
    if (memcmp(want, got, 6) == 0) {
        res->in_order++;
        (*expect)++;
        return;
    }
    for (d = 1; d <= 256 && d <= *expect; d++) { /* an earlier record again? */
        att_link2_sim_record(*expect - d, cfg->report_every, want);
        if (memcmp(want, got, 6) == 0) {
            res->duplicates++;
            return;
        }
    }
    for (d = 1; d <= 256; d++) { /* a later one: records skipped */
        att_link2_sim_record(*expect + d, cfg->report_every, want);
        if (memcmp(want, got, 6) == 0) {
            res->lost += d;
            *expect += d + 1u;
            return;
        }
    }
    res->corrupt++;
}

int att_link2_sim_run(const att_link2_sim_config *cfg, att_link_channel *ch, att_link2_sim_result *res)
{
    uint8_t ring[ATT_LINK2_RING_MAX * 6];
    uint8_t out[ATT_LINK2_OUT_MAX];
    att_link2_sender_stats last;
    att_link2_sender a;
    att_link2_receiver b;
    uint64_t t = 0, next_offer = 0, next_consume = 0, expect = 0, queued = 0, offered = 0;
    uint8_t rec[6], byte, o[ATT_LINK_SIM_MAX_OUT], a_base = 0;
    inbox to_b = { { 0 }, 0 }, to_a = { { 0 }, 0 };
    int st, i, n, k;
    uint64_t step = cfg->ticks_per_byte ? cfg->ticks_per_byte : 10u;
    if (cfg == NULL || ch == NULL || res == NULL) {
        return ATT_E_NULL;
    }
    memset(res, 0, sizeof(*res));
    st = att_link2_sender_init(&a, &cfg->sender, ring);
    if (st != ATT_OK) {
        return st;
    }
    last = a.stats;
    (void)att_link2_receiver_init(&b, out);
    att_link2_receiver_set_room(&b, cfg->queue ? (uint16_t)(cfg->queue > 0xFFFFu ? 0xFFFFu : cfg->queue)
                                               : 0xFFFFu);
    for (;;) {
        /* bytes that arrived during the last byte time */
        for (i = 0; i < to_b.n; i++) {
            st = att_link2_receiver_sink(&b, to_b.bytes[i]);
            if (st == ATT_LINK2_DELIVERED) {
                for (k = 0; k < b.n_out; k++) {
                    check_record(cfg, res, &expect, out + 6 * k);
                }
                queued += b.n_out;
                res->last_delivery_tick = t;
            }
        }
        to_b.n = 0;
        for (i = 0; i < to_a.n; i++) {
            (void)att_link2_sender_sink(&a, to_a.bytes[i], (uint16_t)t);
            if (a.base != a_base) {
                res->acked += (uint8_t)(a.base - a_base);
                a_base = a.base;
            }
        }
        to_a.n = 0;
        /* reboots */
        if (cfg->reboot_sender_tick && t >= cfg->reboot_sender_tick && t < cfg->reboot_sender_tick + step) {
            att_link2_sender_reset(&a);
            a_base = 0;
        }
        if (cfg->reboot_receiver_tick && t >= cfg->reboot_receiver_tick
            && t < cfg->reboot_receiver_tick + step) {
            att_link2_receiver_reset(&b);
        }
        /* consumer: takes one record every consume_period ticks, gives the room back */
        if (cfg->queue) {
            if (!cfg->consume_period) {
                queued = 0;
            } else {
                if (queued == 0 || next_consume + cfg->consume_period < t) {
                    next_consume = queued ? next_consume : t + cfg->consume_period;
                }
                while (queued && t >= next_consume) {
                    queued--;
                    next_consume += cfg->consume_period;
                }
            }
            att_link2_receiver_set_room(&b, (uint16_t)(cfg->queue - queued));
        } else {
            att_link2_receiver_set_room(&b, 0xFFFFu);
        }
        /* producer */
        while (offered < cfg->n_records && t >= next_offer) {
            /* numbered by records pushed: a record the source drops (ring full) is no gap in the stream */
            att_link2_sim_record(res->offered, cfg->report_every, rec);
            if (att_link2_sender_push(&a, rec) == ATT_OK) {
                res->offered++;
            } else if (cfg->period) {
                res->dropped_full++;
            } else {
                break; /* as fast as the ring allows: offer again later */
            }
            offered++;
            next_offer = cfg->period ? next_offer + cfg->period : t;
        }
        /* each end hands out one byte per byte time */
        do {
            st = att_link2_sender_poll(&a, (uint16_t)t, &byte);
        } while (st == ATT_LINK2_TIMEOUT);
        if (st == ATT_LINK2_SEND) {
            n = att_link_channel_transmit(ch, 0, byte, t, o);
            for (i = 0; i < n; i++) {
                to_b.bytes[to_b.n++] = o[i];
            }
        } else if (st < 0) {
            return st;
        }
        st = att_link2_receiver_poll(&b, &byte);
        if (st == ATT_LINK2_SEND) {
            n = att_link_channel_transmit(ch, 1, byte, t, o);
            for (i = 0; i < n; i++) {
                to_a.bytes[to_a.n++] = o[i];
            }
        }
        /* the sender's 16-bit counters, widened */
        res->s_frames += (uint16_t)(a.stats.frames - last.frames);
        res->s_records += (uint16_t)(a.stats.records - last.records);
        res->s_resent += (uint16_t)(a.stats.resent - last.resent);
        res->s_acks += (uint16_t)(a.stats.acks - last.acks);
        res->s_bad_frames += (uint16_t)(a.stats.bad_frames - last.bad_frames);
        res->s_timeouts += (uint16_t)(a.stats.timeouts - last.timeouts);
        res->s_gobacks += (uint16_t)(a.stats.gobacks - last.gobacks);
        res->s_syns += (uint16_t)(a.stats.syns - last.syns);
        last = a.stats;
        t += step;
        if (cfg->max_ticks && t >= cfg->max_ticks) {
            break;
        }
        if (!cfg->max_ticks && offered >= cfg->n_records && a.head == a.base && to_a.n == 0 && to_b.n == 0) {
            break;
        }
    }
    res->ticks = t;
    res->unacked_end = (uint8_t)(a.head - a.base);
    res->receiver = b.stats;
    return ATT_OK;
}
