/*
 * libattitude host-only: channel model and fast link simulation
 * (see link_sim.h and docs/link.md).
 */
#include "link_sim.h"

#include <math.h>
#include <string.h>

/* -- random numbers: splitmix64 (Steele, Lea, Flood 2014) ------------ */

static uint64_t rng_next(uint64_t *state)
{
    uint64_t z;
    *state += 0x9E3779B97F4A7C15ull;
    z = *state;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Uniform in [0, 1) with 53 random bits. */
static double rng_uniform(uint64_t *state)
{
    return (double)(rng_next(state) >> 11) * (1.0 / 9007199254740992.0);
}

/* Error-free bits before the next flipped one: geometric with p = ber. */
static uint64_t draw_skip(uint64_t *state, double ber)
{
    double u, k;
    if (ber >= 1.0) {
        return 0;
    }
    u = 1.0 - rng_uniform(state); /* (0, 1] */
    k = floor(log(u) / log1p(-ber));
    if (!(k < 1e18)) {
        k = 1e18;
    }
    return (uint64_t)k;
}

static int rate_ok(double p)
{
    return p >= 0.0 && p <= 1.0; /* false for NaN */
}

static int rates_ok(const att_link_fault_rates *r)
{
    return rate_ok(r->ber) && rate_ok(r->p_drop) && rate_ok(r->p_insert) && rate_ok(r->p_duplicate);
}

int att_link_channel_init(att_link_channel *ch, const att_link_channel_config *cfg)
{
    if (ch == NULL || cfg == NULL) {
        return ATT_E_NULL;
    }
    if (!rates_ok(&cfg->a_to_b) || !rates_ok(&cfg->b_to_a) || cfg->n_dead > ATT_LINK_SIM_MAX_DEAD) {
        return ATT_E_ARG;
    }
    memset(ch, 0, sizeof(*ch));
    ch->cfg = *cfg;
    ch->rng = cfg->seed;
    if (cfg->a_to_b.ber > 0.0) {
        ch->skip[0] = draw_skip(&ch->rng, cfg->a_to_b.ber);
    }
    if (cfg->b_to_a.ber > 0.0) {
        ch->skip[1] = draw_skip(&ch->rng, cfg->b_to_a.ber);
    }
    return ATT_OK;
}

static int line_dead(const att_link_channel *ch, uint64_t t)
{
    uint32_t i;
    for (i = 0; i < ch->cfg.n_dead; i++) {
        if (t >= ch->cfg.dead_start[i] && t - ch->cfg.dead_start[i] < ch->cfg.dead_length[i]) {
            return 1;
        }
    }
    return 0;
}

int att_link_channel_transmit(att_link_channel *ch, int dir, uint8_t byte, uint64_t t, uint8_t *out)
{
    const att_link_fault_rates *r;
    att_link_channel_stats *st;
    int n = 0;
    int bit;
    uint8_t flips = 0;
    if (ch == NULL || out == NULL) {
        return ATT_E_NULL;
    }
    if (dir != ATT_LINK_DIR_A_TO_B && dir != ATT_LINK_DIR_B_TO_A) {
        return ATT_E_ARG;
    }
    r = dir == ATT_LINK_DIR_A_TO_B ? &ch->cfg.a_to_b : &ch->cfg.b_to_a;
    st = &ch->stats[dir];
    st->bytes++;
    if (line_dead(ch, t)) {
        st->dead++;
        return 0;
    }
    if (r->p_drop > 0.0 && rng_uniform(&ch->rng) < r->p_drop) {
        st->dropped++;
        return 0;
    }
    if (r->p_insert > 0.0 && rng_uniform(&ch->rng) < r->p_insert) {
        out[n++] = (uint8_t)(rng_next(&ch->rng) & 0xFFu);
        st->inserted++;
    }
    if (r->ber > 0.0) {
        for (bit = 0; bit < 8; bit++) {
            if (ch->skip[dir] == 0) {
                flips = (uint8_t)(flips | (1u << bit));
                st->bit_flips++;
                ch->skip[dir] = draw_skip(&ch->rng, r->ber);
            } else {
                ch->skip[dir]--;
            }
        }
    }
    if (flips != 0) {
        st->corrupted++;
    }
    out[n++] = (uint8_t)(byte ^ flips);
    if (r->p_duplicate > 0.0 && rng_uniform(&ch->rng) < r->p_duplicate) {
        out[n++] = (uint8_t)(byte ^ flips);
        st->duplicated++;
    }
    return n;
}

/* -- the simulation --------------------------------------------------- */

typedef struct {
    uint64_t arrival;
    int64_t tag;
    uint8_t byte;
} flight;

typedef struct {
    flight f[ATT_LINK_SIM_MAX_OUT * 2];
    int n;
    uint64_t busy_until; /* line free from this tick */
} line;

typedef struct {
    att_link_sender_stats last;
} sender_ext;

static void extend(att_link_sim_result *res, sender_ext *x, const att_link_sender_stats *s)
{
    res->s_blocks_sent += (uint16_t)(s->blocks_sent - x->last.blocks_sent);
    res->s_blocks_accepted += (uint16_t)(s->blocks_accepted - x->last.blocks_accepted);
    res->s_naks += (uint16_t)(s->naks - x->last.naks);
    res->s_timeouts += (uint16_t)(s->timeouts - x->last.timeouts);
    res->s_gave_up += (uint16_t)(s->gave_up - x->last.gave_up);
    res->s_bytes_discarded += (uint16_t)(s->bytes_discarded - x->last.bytes_discarded);
    x->last = *s;
}

static int put_on_line(att_link_channel *ch, line *ln, int dir, uint8_t byte, int64_t tag, uint64_t t,
                       uint16_t tpb)
{
    uint8_t out[ATT_LINK_SIM_MAX_OUT];
    int k;
    int n = att_link_channel_transmit(ch, dir, byte, t, out);
    if (n < 0) {
        return n;
    }
    for (k = 0; k < n; k++) {
        ln->f[ln->n].arrival = t + tpb;
        ln->f[ln->n].tag = tag;
        ln->f[ln->n].byte = out[k];
        ln->n++;
    }
    ln->busy_until = t + tpb;
    return ATT_OK;
}

static uint64_t min_u64(uint64_t a, uint64_t b)
{
    return a < b ? a : b;
}

int att_link_sim_run(const att_link_sim_config *cfg, att_link_channel *ch, const uint8_t *blocks,
                     uint32_t n_blocks, uint8_t *acc_data, int64_t *acc_index, uint64_t *acc_tick,
                     uint32_t acc_capacity, uint8_t *outcome, att_link_sim_result *res)
{
    att_link_sender a;
    att_link_receiver b;
    uint8_t rxbuf[ATT_LINK_BLOCK_MAX];
    line la, lb; /* la: A -> B, lb: B -> A */
    sender_ext ext;
    uint64_t t = 0;
    uint32_t k = 0;   /* next block to start */
    int64_t cur = -1; /* block A is sending */
    uint32_t reb_done = 0;
    uint8_t n;
    int rc, i, j;

    if (cfg == NULL || ch == NULL || res == NULL || (blocks == NULL && n_blocks > 0)
        || (acc_capacity > 0 && (acc_data == NULL || acc_index == NULL || acc_tick == NULL))) {
        return ATT_E_NULL;
    }
    if (cfg->ticks_per_byte == 0 || cfg->n_reboots > ATT_LINK_SIM_MAX_REBOOTS
        || cfg->sender.block_size != cfg->receiver.block_size) {
        return ATT_E_ARG;
    }
    rc = att_link_sender_init(&a, &cfg->sender);
    if (rc != ATT_OK) {
        return rc;
    }
    rc = att_link_receiver_init(&b, &cfg->receiver, rxbuf);
    if (rc != ATT_OK) {
        return rc;
    }
    n = cfg->sender.block_size;
    memset(res, 0, sizeof(*res));
    memset(&la, 0, sizeof la);
    memset(&lb, 0, sizeof lb);
    memset(&ext, 0, sizeof ext);
    if (outcome != NULL && n_blocks > 0) {
        memset(outcome, ATT_LINK_OUTCOME_PENDING, n_blocks);
    }

    for (;;) {
        uint16_t t16 = (uint16_t)t;
        uint64_t next = UINT64_MAX;
        uint16_t left;
        att_link_result r;
        uint8_t out;

        /* 0. reboots due now (in the order given) */
        for (i = 0; i < (int)cfg->n_reboots; i++) {
            if (!(reb_done & (1u << i)) && cfg->reboot_tick[i] <= t) {
                reb_done |= 1u << i;
                if (cfg->reboot_who[i] == ATT_LINK_REBOOT_SENDER) {
                    if (cur >= 0 && outcome != NULL && outcome[cur] == ATT_LINK_OUTCOME_PENDING) {
                        outcome[cur] = ATT_LINK_OUTCOME_LOST_REBOOT;
                    }
                    cur = -1;
                    att_link_sender_reset(&a);
                } else {
                    att_link_receiver_reset(&b);
                }
            }
        }
        /* 1. bytes arriving at B, then at A */
        for (i = 0; i < la.n && la.f[i].arrival <= t; i++) {
            r = att_link_receiver_sink(&b, la.f[i].byte, t16);
            if (r < 0) {
                return r;
            }
            if (r == ATT_LINK_ACCEPTED) {
                if (res->n_accepted < acc_capacity) {
                    memcpy(acc_data + (size_t)res->n_accepted * n, rxbuf, n);
                    acc_index[res->n_accepted] = la.f[i].tag;
                    acc_tick[res->n_accepted] = t;
                }
                res->n_accepted++;
            }
        }
        for (j = 0; i < la.n; i++, j++) {
            la.f[j] = la.f[i];
        }
        la.n = j;
        for (i = 0; i < lb.n && lb.f[i].arrival <= t; i++) {
            r = att_link_sender_sink(&a, lb.f[i].byte, t16);
            if (r < 0) {
                return r;
            }
            if (r == ATT_LINK_ACCEPTED && cur >= 0) {
                if (outcome != NULL) {
                    outcome[cur] = ATT_LINK_OUTCOME_ACKED;
                }
                cur = -1;
                extend(res, &ext, &a.stats);
            }
        }
        for (j = 0; i < lb.n; i++, j++) {
            lb.f[j] = lb.f[i];
        }
        lb.n = j;
        /* 2. A (polled when its line can take a byte, like the 8051 on TI) */
        if (la.busy_until <= t) {
            for (;;) {
                r = att_link_sender_poll(&a, t16, &out);
                if (r < 0) {
                    return r;
                }
                if (r == ATT_LINK_IDLE) {
                    if (k >= n_blocks) {
                        break;
                    }
                    rc = att_link_sender_start(&a, blocks + (size_t)k * n, t16);
                    if (rc != ATT_OK) {
                        return rc;
                    }
                    cur = (int64_t)k;
                    k++;
                    res->blocks_started = k;
                    continue;
                }
                if (r == ATT_LINK_SEND) {
                    rc = put_on_line(ch, &la, ATT_LINK_DIR_A_TO_B, out, cur, t, cfg->ticks_per_byte);
                    if (rc != ATT_OK) {
                        return rc;
                    }
                    break;
                }
                if (r == ATT_LINK_GAVE_UP) {
                    if (cur >= 0 && outcome != NULL) {
                        outcome[cur] = ATT_LINK_OUTCOME_GAVE_UP;
                    }
                    cur = -1;
                    extend(res, &ext, &a.stats);
                    continue;
                }
                if (r == ATT_LINK_NONE) {
                    break;
                }
                /* ATT_LINK_TIMEOUT: keep polling */
            }
        }
        /* 3. B */
        if (lb.busy_until <= t) {
            for (;;) {
                r = att_link_receiver_poll(&b, t16, &out);
                if (r < 0) {
                    return r;
                }
                if (r == ATT_LINK_SEND) {
                    rc = put_on_line(ch, &lb, ATT_LINK_DIR_B_TO_A, out, -1, t, cfg->ticks_per_byte);
                    if (rc != ATT_OK) {
                        return rc;
                    }
                    break;
                }
                if (r == ATT_LINK_NONE || r == ATT_LINK_IDLE) {
                    break;
                }
            }
        }
        /* 4. done? all blocks finished by A, nothing on the wires */
        left = att_link_sender_ticks_left(&a, t16);
        if (k >= n_blocks && cur < 0 && left == (uint16_t)ATT_LINK_NO_TIMER && la.n == 0 && lb.n == 0
            && la.busy_until <= t && lb.busy_until <= t) {
            break;
        }
        /* 5. next event */
        if (la.n > 0) {
            next = min_u64(next, la.f[0].arrival);
        }
        if (lb.n > 0) {
            next = min_u64(next, lb.f[0].arrival);
        }
        if (la.busy_until > t) {
            next = min_u64(next, la.busy_until);
        } else if (left != (uint16_t)ATT_LINK_NO_TIMER) {
            next = min_u64(next, t + (left == 0 ? 1u : left));
        }
        if (lb.busy_until > t) {
            next = min_u64(next, lb.busy_until);
        } else {
            left = att_link_receiver_ticks_left(&b, t16);
            if (left != (uint16_t)ATT_LINK_NO_TIMER) {
                next = min_u64(next, t + (left == 0 ? 1u : left));
            }
        }
        for (i = 0; i < (int)cfg->n_reboots; i++) {
            if (!(reb_done & (1u << i))) {
                next = min_u64(next, cfg->reboot_tick[i] > t ? cfg->reboot_tick[i] : t + 1);
            }
        }
        if (next == UINT64_MAX) {
            break; /* nothing can happen any more */
        }
        if (cfg->max_ticks != 0 && next > cfg->max_ticks) {
            t = cfg->max_ticks;
            break;
        }
        t = next;
    }
    extend(res, &ext, &a.stats);
    res->ticks = t;
    res->receiver = b.stats;
    return ATT_OK;
}
