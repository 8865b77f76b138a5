/*
 * libFuzzer target for the link machines (attitude/link.h), built with
 * AddressSanitizer + UndefinedBehaviorSanitizer (`invoke fuzz`).
 *
 * Input: byte 0 = block size (1..64), bytes 1-2 = gap timeout, then pairs
 * (control, byte): the low nibble of `control` advances the tick
 * (x 1, or x 256 if bit 4 is set, so waits cross the 16-bit wrap), bit 5
 * skips the poll after the byte. The byte is fed to a receiver and to a
 * sender (which is kept busy with a block). Invariants are checked with
 * abort(): valid results only, index within the block, a bounded number
 * of bytes brings the receiver back to idle.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "attitude/link.h"

static void check(int cond)
{
    if (!cond) {
        abort();
    }
}

static void drain_receiver(att_link_receiver *r, uint16_t tick)
{
    uint8_t out = 0;
    int guard = 0;
    att_link_result res;
    while ((res = att_link_receiver_poll(r, tick, &out)) != ATT_LINK_NONE && res != ATT_LINK_IDLE) {
        check(res == ATT_LINK_SEND || res == ATT_LINK_TIMEOUT);
        if (res == ATT_LINK_SEND) {
            check(out == 0xBB || out == 0x00 || out == 0xFF);
        }
        check(++guard < 4);
    }
}

static void drain_sender(att_link_sender *s, uint16_t tick, const uint8_t *blk)
{
    uint8_t out = 0;
    int guard = 0;
    att_link_result res;
    for (;;) {
        res = att_link_sender_poll(s, tick, &out);
        check(res >= 0);
        if (res == ATT_LINK_IDLE) {
            check(att_link_sender_start(s, blk, tick) == ATT_OK);
        } else if (res == ATT_LINK_NONE) {
            break;
        }
        check(++guard < 200);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    att_link_receiver r;
    att_link_receiver_config rc;
    att_link_sender s;
    att_link_sender_config sc;
    uint8_t buf[ATT_LINK_BLOCK_MAX];
    uint8_t blk[ATT_LINK_BLOCK_MAX];
    uint16_t tick = 0;
    size_t i;
    int k;
    if (size < 3) {
        return 0;
    }
    att_link_receiver_config_init(&rc, (uint8_t)(data[0] % ATT_LINK_BLOCK_MAX + 1));
    rc.gap_timeout = (uint16_t)(((uint16_t)data[1] << 8 | data[2]) % ATT_LINK_TIMEOUT_MAX + 1);
    check(att_link_receiver_init(&r, &rc, buf) == ATT_OK);
    att_link_sender_config_init(&sc, rc.block_size);
    sc.syn_timeout = rc.gap_timeout;
    sc.answer_timeout = (uint16_t)(rc.gap_timeout / 2 + 1);
    sc.max_attempts = (uint8_t)(data[0] % 7 + 1);
    check(att_link_sender_init(&s, &sc) == ATT_OK);
    memcpy(blk, data, size < sizeof blk ? size : sizeof blk);
    for (i = 3; i + 1 < size; i += 2) {
        uint8_t ctl = data[i];
        uint8_t byte = data[i + 1];
        att_link_result res;
        tick = (uint16_t)(tick + (uint16_t)((ctl & 0x0F) * ((ctl & 0x10) ? 256u : 1u)));
        res = att_link_receiver_sink(&r, byte, tick);
        check(res == ATT_LINK_DISCARDED || res == ATT_LINK_SYN_RX || res == ATT_LINK_DATA_RX
              || res == ATT_LINK_ACCEPTED || res == ATT_LINK_REJECTED);
        check(r.index <= r.cfg.block_size);
        if (res == ATT_LINK_ACCEPTED) {
            check(att_link_checksum(buf, r.cfg.block_size) == byte);
        }
        res = att_link_sender_sink(&s, byte, tick);
        check(res == ATT_LINK_DISCARDED || res == ATT_LINK_SYN_RX || res == ATT_LINK_ACCEPTED
              || res == ATT_LINK_REJECTED);
        if (!(ctl & 0x20)) {
            drain_receiver(&r, tick);
            drain_sender(&s, tick, blk);
        }
        check(s.index <= s.cfg.block_size);
    }
    /* bounded return to idle: at most N + 1 more bytes (no 0xAA) end any block */
    drain_receiver(&r, tick);
    for (k = 0; k <= r.cfg.block_size; k++) {
        check(att_link_receiver_sink(&r, 0x00, tick) >= 0);
        drain_receiver(&r, tick);
    }
    {
        uint8_t out;
        check(att_link_receiver_poll(&r, tick, &out) == ATT_LINK_IDLE);
    }
    /* and silence longer than the gap timeout always ends a block too */
    check(att_link_receiver_sink(&r, 0xAA, tick) == ATT_LINK_SYN_RX);
    drain_receiver(&r, tick);
    {
        uint8_t out;
        check(att_link_receiver_poll(&r, (uint16_t)(tick + rc.gap_timeout + 1u), &out) == ATT_LINK_TIMEOUT);
        check(att_link_receiver_poll(&r, (uint16_t)(tick + rc.gap_timeout + 1u), &out) == ATT_LINK_IDLE);
    }
    return 0;
}
