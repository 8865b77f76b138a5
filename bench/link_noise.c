/*
 * Line noise through the legacy link protocol: what random bytes become.
 *
 * Feeds MIB mebibytes of uniformly random bytes (splitmix64, SEED) into the
 * link receiver B (attitude/link.h) back to back (no gaps, so no timeouts),
 * N = 6, and decodes every block B accepts with the block decoder
 * (attitude/block.h), as attitude-rx does. Prints one JSON object: bytes,
 * handshakes (0xAA taken), accepted blocks, and what the accepted records
 * decode to: good samples (plausible garbage: all codes <= 4095), samples
 * rejected for a code > 4095, valid reports per kind, rejected reports.
 *
 * Usage: link_noise MIB SEED   (bench/rx.py builds and runs it)
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>

#include "attitude/block.h"
#include "attitude/link.h"

static uint64_t splitmix64(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

int main(int argc, char **argv)
{
    att_link_receiver r;
    att_link_receiver_config rc;
    uint8_t blk[ATT_BLOCK_SIZE], out;
    uint64_t seed, n, i, accepted = 0, good = 0, bad_code = 0, bad_report = 0, kinds[5] = { 0 };
    if (argc != 3) {
        fprintf(stderr, "usage: %s MIB SEED\n", argv[0]);
        return 2;
    }
    n = strtoull(argv[1], NULL, 10) << 20;
    seed = strtoull(argv[2], NULL, 10);
    att_link_receiver_config_init(&rc, ATT_BLOCK_SIZE);
    if (att_link_receiver_init(&r, &rc, blk) != ATT_OK)
        return 1;
    for (i = 0; i < n; i += 8) {
        uint64_t w = splitmix64(&seed);
        int k;
        for (k = 0; k < 8; k++, w >>= 8) {
            if (att_link_receiver_sink(&r, (uint8_t)w, 0) == ATT_LINK_ACCEPTED) {
                att_block b;
                int st = att_block_decode(blk, &b);
                accepted++;
                if (st == ATT_OK && b.kind == ATT_BLOCK_SAMPLE)
                    good++;
                else if (st == ATT_BLOCK_E_CODE)
                    bad_code++;
                else if (st == ATT_OK)
                    kinds[b.kind]++;
                else
                    bad_report++;
            }
            while (att_link_receiver_poll(&r, 0, &out) == ATT_LINK_SEND) {
            }
        }
    }
    printf("{\"bytes\": %" PRIu64 ", \"handshakes\": %" PRIu32 ", \"accepted\": %" PRIu64
           ", \"good_samples\": %" PRIu64 ", \"bad_code\": %" PRIu64 ", \"boot\": %" PRIu64
           ", \"selftest\": %" PRIu64 ", \"gave_up\": %" PRIu64 ", \"overrun\": %" PRIu64
           ", \"adc_error\": %" PRIu64 ", \"bad_report\": %" PRIu64 "}\n",
           n, r.stats.syns, accepted, good, bad_code, kinds[0], kinds[1], kinds[2], kinds[3], kinds[4],
           bad_report);
    return 0;
}
