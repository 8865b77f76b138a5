/*
 * libattitude — GNSS parser framing (attitude/gnss.h, docs/gnss.md).
 *
 * The link's style (link_receiver.c): one function per state, each taking
 * one byte. HUNT looks for '$' (an NMEA sentence) or 0xB5 (a UBX frame);
 * the NMEA states gather the body and its XOR checksum, the UBX states the
 * header, the payload (stored only for NAV-PVT) and the Fletcher checksum.
 * A byte that ends a message wrongly (a non-printable byte in a sentence,
 * a lone 0xB5) is taken again by HUNT, so what follows is not lost.
 */
#include "gnss_internal.h"

typedef enum {
    GS_HUNT = 0,  /* between messages */
    GS_NMEA_BODY, /* after '$': characters up to '*' */
    GS_NMEA_CK1,  /* after '*': first checksum hex digit */
    GS_NMEA_CK2,  /* second checksum hex digit */
    GS_UBX_SYNC2, /* after 0xB5: 0x62 */
    GS_UBX_CLASS,
    GS_UBX_ID,
    GS_UBX_LEN1, /* length, low byte */
    GS_UBX_LEN2, /* length, high byte */
    GS_UBX_PAYLOAD,
    GS_UBX_CKA,
    GS_UBX_CKB,
    GS_COUNT
} gs_state;

static void go(att_gnss_parser *p, gs_state s)
{
    p->state = (uint8_t)s;
}

/* Value of a hex digit (either case), or -1. */
static int hex_value(uint8_t c)
{
    if (c >= '0' && c <= '9') {
        return c - '0';
    }
    if (c >= 'A' && c <= 'F') {
        return c - 'A' + 10;
    }
    if (c >= 'a' && c <= 'f') {
        return c - 'a' + 10;
    }
    return -1;
}

static void fletcher(att_gnss_parser *p, uint8_t byte)
{
    p->sum = (uint8_t)(p->sum + byte);
    p->sum_b = (uint8_t)(p->sum_b + p->sum);
}

static att_gnss_result hunt(att_gnss_parser *p, uint8_t byte)
{
    if (byte == '$') {
        p->len = 0;
        p->sum = 0;
        go(p, GS_NMEA_BODY);
    } else if (byte == (uint8_t)ATT_GNSS_UBX_SYNC1) {
        go(p, GS_UBX_SYNC2);
    } else if (byte != '\r' && byte != '\n') {
        p->stats.bytes_skipped++;
    }
    return ATT_GNSS_NONE;
}

/* A sentence cut: counted, and the byte that cut it starts what follows. */
static att_gnss_result cut(att_gnss_parser *p, uint8_t byte)
{
    p->stats.truncated++;
    go(p, GS_HUNT);
    (void)hunt(p, byte);
    return ATT_GNSS_REJECTED;
}

static att_gnss_result nmea_body(att_gnss_parser *p, uint8_t byte)
{
    if (byte == '*') {
        go(p, GS_NMEA_CK1);
        return ATT_GNSS_NONE;
    }
    if (byte == '$' || byte < 0x20 || byte > 0x7E) {
        return cut(p, byte);
    }
    if (p->len >= (uint16_t)ATT_GNSS_NMEA_BODY) {
        p->stats.overruns++;
        go(p, GS_HUNT);
        return ATT_GNSS_REJECTED;
    }
    p->buf[p->len++] = byte;
    p->sum ^= byte;
    return ATT_GNSS_NONE;
}

static att_gnss_result nmea_ck1(att_gnss_parser *p, uint8_t byte)
{
    int v = hex_value(byte);
    if (v < 0) {
        return cut(p, byte);
    }
    p->sum_b = (uint8_t)v;
    go(p, GS_NMEA_CK2);
    return ATT_GNSS_NONE;
}

static att_gnss_result nmea_ck2(att_gnss_parser *p, uint8_t byte, att_gnss_fix *out)
{
    int v = hex_value(byte);
    if (v < 0) {
        return cut(p, byte);
    }
    go(p, GS_HUNT);
    if ((uint8_t)(p->sum_b << 4 | v) != p->sum) {
        p->stats.bad_checksum++;
        return ATT_GNSS_REJECTED;
    }
    return att__gnss_nmea(p, out);
}

static att_gnss_result ubx_sync2(att_gnss_parser *p, uint8_t byte)
{
    if (byte != (uint8_t)ATT_GNSS_UBX_SYNC2) {
        p->stats.bytes_skipped++; /* the lone 0xB5 */
        go(p, GS_HUNT);
        return hunt(p, byte);
    }
    p->sum = 0;
    p->sum_b = 0;
    go(p, GS_UBX_CLASS);
    return ATT_GNSS_NONE;
}

static int is_pvt(const att_gnss_parser *p)
{
    return p->ubx_class == (uint8_t)ATT_GNSS_UBX_NAV && p->ubx_id == (uint8_t)ATT_GNSS_UBX_PVT;
}

/* Class, id and the length's two bytes. */
static att_gnss_result ubx_header(att_gnss_parser *p, uint8_t byte)
{
    fletcher(p, byte);
    switch (p->state) {
    case GS_UBX_CLASS:
        p->ubx_class = byte;
        go(p, GS_UBX_ID);
        return ATT_GNSS_NONE;
    case GS_UBX_ID:
        p->ubx_id = byte;
        go(p, GS_UBX_LEN1);
        return ATT_GNSS_NONE;
    case GS_UBX_LEN1:
        p->ubx_len = byte;
        go(p, GS_UBX_LEN2);
        return ATT_GNSS_NONE;
    default:
        break;
    }
    p->ubx_len = (uint16_t)(p->ubx_len | (uint16_t)byte << 8);
    p->len = 0;
    if (p->ubx_len > (uint16_t)ATT_GNSS_UBX_SKIP_MAX || (is_pvt(p) && p->ubx_len != ATT_GNSS_UBX_PVT_LEN)) {
        p->stats.overruns++;
        go(p, GS_HUNT);
        return ATT_GNSS_REJECTED;
    }
    go(p, p->ubx_len == 0 ? GS_UBX_CKA : GS_UBX_PAYLOAD);
    return ATT_GNSS_NONE;
}

static att_gnss_result ubx_payload(att_gnss_parser *p, uint8_t byte)
{
    fletcher(p, byte);
    if (is_pvt(p)) {
        p->buf[p->len] = byte;
    }
    p->len++;
    if (p->len >= p->ubx_len) {
        go(p, GS_UBX_CKA);
    }
    return ATT_GNSS_NONE;
}

static att_gnss_result ubx_ck(att_gnss_parser *p, uint8_t byte, att_gnss_fix *out)
{
    uint8_t want = p->state == (uint8_t)GS_UBX_CKA ? p->sum : p->sum_b;
    if (byte != want) {
        p->stats.bad_checksum++;
        go(p, GS_HUNT);
        return ATT_GNSS_REJECTED;
    }
    if (p->state == (uint8_t)GS_UBX_CKA) {
        go(p, GS_UBX_CKB);
        return ATT_GNSS_NONE;
    }
    go(p, GS_HUNT);
    if (!is_pvt(p)) {
        p->stats.ignored++;
        return ATT_GNSS_IGNORED;
    }
    return att__gnss_nav_pvt(p, out);
}

static int corrupted(const att_gnss_parser *p)
{
    uint8_t s = p->state;
    int nmea = s >= (uint8_t)GS_NMEA_BODY && s <= (uint8_t)GS_NMEA_CK2;
    int payload = s == (uint8_t)GS_UBX_PAYLOAD || s == (uint8_t)GS_UBX_CKA || s == (uint8_t)GS_UBX_CKB;
    return s >= (uint8_t)GS_COUNT || (nmea && p->len > (uint16_t)ATT_GNSS_NMEA_BODY)
           || (payload && (p->ubx_len > (uint16_t)ATT_GNSS_UBX_SKIP_MAX || p->len > p->ubx_len))
           || (payload && is_pvt(p) && p->ubx_len != ATT_GNSS_UBX_PVT_LEN)
           || p->epoch_open > (ATT__GNSS_OPEN | ATT__GNSS_TIMED);
}

int att_gnss_init(att_gnss_parser *p)
{
    static const att_gnss_parser zero = { 0 };
    if (p == NULL) {
        return ATT_GNSS_E_NULL;
    }
    *p = zero;
    return ATT_OK;
}

att_gnss_result att_gnss_feed(att_gnss_parser *p, uint8_t byte, att_gnss_fix *out)
{
    if (p == NULL || out == NULL) {
        return ATT_GNSS_E_NULL;
    }
    if (corrupted(p)) {
        return ATT_GNSS_E_STATE;
    }
    p->stats.bytes++;
    switch (p->state) {
    case GS_HUNT:
        return hunt(p, byte);
    case GS_NMEA_BODY:
        return nmea_body(p, byte);
    case GS_NMEA_CK1:
        return nmea_ck1(p, byte);
    case GS_NMEA_CK2:
        return nmea_ck2(p, byte, out);
    case GS_UBX_SYNC2:
        return ubx_sync2(p, byte);
    case GS_UBX_PAYLOAD:
        return ubx_payload(p, byte);
    case GS_UBX_CKA:
    case GS_UBX_CKB:
        return ubx_ck(p, byte, out);
    default:
        return ubx_header(p, byte);
    }
}

int att_gnss_feed_buf(att_gnss_parser *p, const uint8_t *data, size_t n, att_gnss_fix *fixes, size_t cap,
                      size_t *used, size_t *n_fix)
{
    size_t i, k = 0;
    if (p == NULL || used == NULL || n_fix == NULL || (data == NULL && n > 0) || (fixes == NULL && cap > 0)) {
        return ATT_GNSS_E_NULL;
    }
    if (corrupted(p)) {
        return ATT_GNSS_E_STATE;
    }
    for (i = 0; i < n && k < cap; i++) {
        if (att_gnss_feed(p, data[i], &fixes[k]) == ATT_GNSS_FIX) {
            k++;
        }
    }
    *used = i;
    *n_fix = k;
    return ATT_OK;
}

att_gnss_result att_gnss_flush(att_gnss_parser *p, att_gnss_fix *out)
{
    if (p == NULL || out == NULL) {
        return ATT_GNSS_E_NULL;
    }
    if (corrupted(p)) {
        return ATT_GNSS_E_STATE;
    }
    if (!(p->epoch_open & ATT__GNSS_OPEN)) {
        return ATT_GNSS_NONE;
    }
    att__gnss_close_epoch(p, out);
    return ATT_GNSS_FIX;
}
