/*
 * libattitude — block format encoders of oversampled streams (see
 * attitude/block.h): the OVERSAMPLE report and sample records of sums.
 * Host-side boards use them (the simulator's modeled board), and so does the
 * aided AT89S52 firmware built with gyro oversampling (FW_GYRO_OVERSAMPLE); kept
 * out of block.c so that the AT89S51 firmware, which sends plain codes, links
 * exactly what it did.
 */
#include "attitude/block.h"

int att_block_encode_oversample(uint8_t ATT_LINK_MEM *blk, uint8_t n)
{
    if (blk == NULL) {
        return ATT_E_NULL;
    }
    if (n < 1u || n > (uint8_t)ATT_BLOCK_OVERSAMPLE_MAX) {
        return ATT_BLOCK_E_FIELD;
    }
    *blk++ = (uint8_t)ATT_BLOCK_MARK;
    *blk++ = (uint8_t)ATT_BLOCK_OVERSAMPLE;
    *blk++ = n;
    *blk++ = 0u;
    *blk++ = 0u;
    *blk = 0u;
    return ATT_OK;
}

int att_block_encode_sums(uint8_t ATT_LINK_MEM *blk, const uint16_t ATT_LINK_MEM *sums, uint8_t n)
{
    uint16_t limit;
    uint8_t i;
    if (blk == NULL || sums == NULL) {
        return ATT_E_NULL;
    }
    if (n < 1u || n > (uint8_t)ATT_BLOCK_OVERSAMPLE_MAX) {
        return ATT_BLOCK_E_FIELD;
    }
    /* n x 4095 as n x 4096 - n in 16 bits (16 x 4095 = 65520 fits): no multiplication, so
     * on the 8051 (the aided board's gyro oversampling) this stays a leaf function whose
     * locals SDCC overlays */
    limit = (uint16_t)((uint16_t)((uint16_t)n << 12) - (uint16_t)n);
    if (limit > (uint16_t)ATT_BLOCK_SUM_MAX) {
        limit = (uint16_t)ATT_BLOCK_SUM_MAX;
    }
    for (i = 0; i < 3u; i++) {
        if (sums[i] > limit) {
            return ATT_BLOCK_E_CODE;
        }
    }
    /* checked first, so an error leaves blk as it was (and sums may alias blk) */
    for (i = 0; i < 3u; i++) {
        uint16_t w = sums[i];
        *blk++ = (uint8_t)(w >> 8);
        *blk++ = (uint8_t)w;
    }
    return ATT_OK;
}
