/*
 * libattitude — link v2 receiver B (see attitude/link2.h and docs/link.md).
 *
 * Byte-driven: sink stores encoded bytes up to the delimiter, then decodes
 * the frame (rCOBS, backwards), checks it (CRC, length, type) and applies
 * it; poll hands out the ACK that answers it. For the Linux side (the
 * frame buffers make the state about 450 bytes); C99, no I/O, no malloc.
 */
#include "attitude/link2.h"

enum {
    ACK_DUE = 0x80
}; /* ack_flags: an ACK is queued */

int att_link2_receiver_init(att_link2_receiver *r, uint8_t *out)
{
    uint32_t *p;
    uint8_t i;
    if (r == NULL || out == NULL) {
        return ATT_LINK2_E_NULL;
    }
    r->out = out;
    p = &r->stats.frames;
    for (i = 0; i < (uint8_t)(sizeof(r->stats) / sizeof(uint32_t)); i++) {
        p[i] = 0;
    }
    r->room = 0;
    att_link2_receiver_reset(r);
    return ATT_OK;
}

void att_link2_receiver_reset(att_link2_receiver *r)
{
    if (r == NULL) {
        return;
    }
    r->n_out = 0;
    r->synced = 0;
    r->expected = 0;
    r->last_limit = 0;
    r->ack_flags = 0;
    r->len = 0;
    r->tx_len = 0;
    r->tx_pos = 0;
}

static uint8_t window(uint16_t room)
{
    return room > (uint16_t)ATT_LINK2_WINDOW_MAX ? (uint8_t)ATT_LINK2_WINDOW_MAX : (uint8_t)room;
}

void att_link2_receiver_set_room(att_link2_receiver *r, uint16_t room)
{
    uint8_t old;
    if (r == NULL) {
        return;
    }
    old = (uint8_t)(r->last_limit - r->expected);
    r->room = room;
    if (r->synced && old < (uint8_t)ATT_LINK2_SAMPLES_MAX && window(room) > old) {
        r->ack_flags |= (uint8_t)ACK_DUE; /* window update: A may be blocked */
    }
}

/* Queue an ACK; the latest frame's flags replace earlier ones, a SYNACK stays. */
static void queue_ack(att_link2_receiver *r, uint8_t flag)
{
    r->ack_flags = (uint8_t)(ACK_DUE | flag | (r->ack_flags & (uint8_t)ATT_LINK2_F_SYNACK));
}

/* The F_EPOCH flag that echoes frame head h. */
static uint8_t epoch(uint8_t h)
{
    return (h & (uint8_t)ATT_LINK2_E_BIT) ? (uint8_t)ATT_LINK2_F_EPOCH : 0u;
}

/* rCOBS-decode buf[0..n) backwards into the end of dec: the frame's length, 0 if malformed. */
static uint8_t decode(att_link2_receiver *r, uint8_t n, uint8_t **frame)
{
    uint8_t p = n;
    uint8_t q = (uint8_t)ATT_LINK2_WIRE_MAX;
    uint8_t code;
    uint8_t run;
    uint8_t first = 1;
    while (p != 0u) {
        code = r->buf[p - 1u];
        run = code == 0xFFu ? 254u : (uint8_t)(code - 1u);
        if ((first && code == 0xFFu) || run > (uint8_t)(p - 1u)) {
            return 0;
        }
        p--;
        if (!first && code != 0xFFu) {
            r->dec[--q] = 0; /* the zero this code stands for */
        }
        first = 0;
        while (run-- != 0u) {
            r->dec[--q] = r->buf[--p];
        }
    }
    *frame = &r->dec[q];
    return (uint8_t)((uint8_t)ATT_LINK2_WIRE_MAX - q);
}

/* Code m of the packed samples at p. */
static uint16_t unpack(const uint8_t *p, uint8_t m)
{
    const uint8_t *b = p + 3u * (uint8_t)(m >> 1);
    if ((m & 1u) == 0u) {
        return (uint16_t)((uint16_t)((uint16_t)b[0] << 4) | (uint16_t)(b[1] >> 4));
    }
    return (uint16_t)((uint16_t)((uint16_t)(b[1] & 0x0Fu) << 8) | b[2]);
}

/* Records seq .. seq + cnt - 1 arrived (cnt 0: a probe): deliver the new ones B has room for. */
static att_link2_result data_frame(att_link2_receiver *r, const uint8_t *f, uint8_t seq, uint8_t cnt)
{
    uint8_t off = (uint8_t)(r->expected - seq);
    uint8_t k;
    uint8_t i;
    uint8_t c;
    uint16_t code;
    if (!r->synced) {
        r->stats.no_session++;
        queue_ack(r, (uint8_t)ATT_LINK2_F_NOSESSION);
        return ATT_LINK2_FRAME;
    }
    if (off > (uint8_t)ATT_LINK2_WINDOW_MAX) { /* starts after expected: something was lost */
        r->stats.gaps++;
        queue_ack(r, (uint8_t)(ATT_LINK2_F_GAP | epoch(f[0])));
        return ATT_LINK2_FRAME;
    }
    queue_ack(r, epoch(f[0]));
    if (off >= cnt) {
        r->stats.duplicates += cnt;
        return ATT_LINK2_FRAME;
    }
    r->stats.duplicates += off;
    k = (uint8_t)(cnt - off);
    if ((uint16_t)k > r->room) {
        r->stats.refused += (uint32_t)(k - (uint8_t)r->room);
        k = (uint8_t)r->room;
    }
    if (k == 0u) {
        return ATT_LINK2_FRAME;
    }
    if (f[0] & (uint8_t)ATT_LINK2_T_RAW) {
        for (i = 0; i < (uint8_t)ATT_LINK2_RECORD; i++) {
            r->out[i] = f[2 + i];
        }
    } else {
        for (i = 0; i < k; i++) {
            for (c = 0; c < 3u; c++) {
                code = unpack(f + 2, (uint8_t)(3u * (uint8_t)(off + i) + c));
                r->out[6u * i + 2u * c] = (uint8_t)(code >> 8);
                r->out[6u * i + 2u * c + 1u] = (uint8_t)code;
            }
        }
    }
    r->expected = (uint8_t)(r->expected + k);
    r->room = (uint16_t)(r->room - k);
    r->stats.records += k;
    r->n_out = k;
    return ATT_LINK2_DELIVERED;
}

/* A decoded frame f[0..len): check and apply it. */
static att_link2_result frame(att_link2_receiver *r, const uint8_t *f, uint8_t len)
{
    uint32_t crc;
    uint8_t h;
    uint8_t n;
    if (len < 6u) {
        goto bad;
    }
    crc = att_link2_crc(f, (uint16_t)(len - 4u));
    if (f[len - 4u] != (uint8_t)(crc >> 24) || f[len - 3u] != (uint8_t)(crc >> 16)
        || f[len - 2u] != (uint8_t)(crc >> 8) || f[len - 1u] != (uint8_t)crc) {
        goto bad;
    }
    h = f[0];
    switch (h & 0xC0u) {
    case ATT_LINK2_T_DATA:
        n = (uint8_t)(h & 0x1Fu);
        if (n > (uint8_t)ATT_LINK2_SAMPLES_MAX || len != (uint8_t)(6u + (uint8_t)((9u * n + 1u) >> 1))
            || ((n & 1u) && (f[len - 5u] & 0x0Fu) != 0u)) {
            goto bad;
        }
        r->stats.frames++;
        return data_frame(r, f, f[1], n);
    case ATT_LINK2_T_RAW:
        if ((h & (uint8_t)~ATT_LINK2_E_BIT) != (uint8_t)ATT_LINK2_T_RAW
            || len != (uint8_t)(6u + (uint8_t)ATT_LINK2_RECORD)) {
            goto bad;
        }
        r->stats.frames++;
        return data_frame(r, f, f[1], 1u);
    case ATT_LINK2_T_SYN:
        if (h != (uint8_t)ATT_LINK2_T_SYN || len != 6u) {
            goto bad;
        }
        r->stats.frames++;
        r->stats.syns++;
        r->synced = 1;
        r->expected = f[1];
        queue_ack(r, (uint8_t)ATT_LINK2_F_SYNACK);
        return ATT_LINK2_FRAME;
    default: /* an ACK travels the other way */
        break;
    }
bad:
    r->stats.bad_frames++;
    return ATT_LINK2_BAD_FRAME;
}

att_link2_result att_link2_receiver_sink(att_link2_receiver *r, uint8_t byte)
{
    uint8_t n;
    uint8_t *f = NULL;
    if (r == NULL) {
        return ATT_LINK2_E_NULL;
    }
    n = r->len;
    if (n != 0xFFu && n > (uint8_t)ATT_LINK2_WIRE_MAX) {
        return ATT_LINK2_E_STATE;
    }
    r->n_out = 0;
    if (byte != (uint8_t)ATT_LINK2_DELIM) {
        if (n == 0xFFu) {
            r->stats.bytes_discarded++;
            return ATT_LINK2_DISCARDED;
        }
        if (n == (uint8_t)ATT_LINK2_WIRE_MAX) { /* longer than any frame: skip to the delimiter */
            r->stats.bytes_discarded += (uint32_t)n + 1u;
            r->len = 0xFFu;
            return ATT_LINK2_DISCARDED;
        }
        r->buf[n] = byte;
        r->len = (uint8_t)(n + 1u);
        return ATT_LINK2_NONE;
    }
    r->len = 0;
    if (n == 0u) {
        return ATT_LINK2_NONE; /* idle delimiter */
    }
    if (n == 0xFFu) {
        r->stats.bad_frames++;
        return ATT_LINK2_BAD_FRAME;
    }
    n = decode(r, n, &f);
    if (n == 0u) {
        r->stats.bad_frames++;
        return ATT_LINK2_BAD_FRAME;
    }
    return frame(r, f, n);
}

/* rCOBS-encode in[0..n) (n < 254) into out: n + 1 bytes, none of them 0. */
static uint8_t encode(const uint8_t *in, uint8_t n, uint8_t *out)
{
    uint8_t i;
    uint8_t run = 0;
    for (i = 0; i < n; i++) {
        if (in[i] == 0u) {
            out[i] = (uint8_t)(run + 1u);
            run = 0;
        } else {
            out[i] = in[i];
            run++;
        }
    }
    out[n] = (uint8_t)(run + 1u);
    return (uint8_t)(n + 1u);
}

att_link2_result att_link2_receiver_poll(att_link2_receiver *r, uint8_t *out_byte)
{
    uint8_t d[7];
    uint32_t crc;
    if (r == NULL || out_byte == NULL) {
        return ATT_LINK2_E_NULL;
    }
    if (r->tx_len > (uint8_t)sizeof(r->tx) || r->tx_pos > r->tx_len) {
        return ATT_LINK2_E_STATE;
    }
    if (r->tx_pos < r->tx_len) {
        *out_byte = r->tx[r->tx_pos++];
        return ATT_LINK2_SEND;
    }
    if ((r->ack_flags & (uint8_t)ACK_DUE) == 0u) {
        return ATT_LINK2_IDLE;
    }
    d[0] = (uint8_t)(ATT_LINK2_T_ACK | (r->ack_flags & 0x0Fu));
    d[1] = r->synced ? r->expected : 0u;
    d[2] = r->synced ? (uint8_t)(r->expected + window(r->room)) : 0u;
    crc = att_link2_crc(d, 3u);
    d[3] = (uint8_t)(crc >> 24);
    d[4] = (uint8_t)(crc >> 16);
    d[5] = (uint8_t)(crc >> 8);
    d[6] = (uint8_t)crc;
    r->last_limit = d[2];
    r->ack_flags = 0;
    r->tx[0] = (uint8_t)ATT_LINK2_DELIM; /* acks are sparse: each leads with a delimiter */
    r->tx_len = (uint8_t)(encode(d, 7u, &r->tx[1]) + 2u);
    r->tx[r->tx_len - 1u] = (uint8_t)ATT_LINK2_DELIM;
    r->stats.acks++;
    r->tx_pos = 1;
    *out_byte = r->tx[0];
    return ATT_LINK2_SEND;
}
