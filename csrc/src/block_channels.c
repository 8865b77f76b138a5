/*
 * libattitude — the CHANNELS report's encoder (see attitude/block.h): what
 * the aided AT89S52 firmware adds to block.c. Kept out of block.c so that
 * the AT89S51 gyro-only image links exactly what it did. The decoder and
 * the sequence tracker (block_decode.c) check a received CHANNELS report
 * with this function too: its range checks are the format's one copy.
 *
 * Portable C99 that SDCC compiles for the 8051 small model: a leaf
 * function with 8-bit arithmetic (SDCC overlays its parameters).
 */
#include "attitude/block.h"

int att_block_encode_channels(uint8_t ATT_LINK_MEM *blk, uint8_t board, uint8_t channels, uint8_t acc_every,
                              uint8_t mag_every)
{
    const uint8_t all = (uint8_t)(ATT_BLOCK_CH_GYR | ATT_BLOCK_CH_ACC | ATT_BLOCK_CH_MAG);
    if (blk == NULL) {
        return ATT_E_NULL;
    }
    if ((channels & (uint8_t)~all) != 0u || (channels & (uint8_t)ATT_BLOCK_CH_GYR) == 0u
        || (board != (uint8_t)ATT_BLOCK_BOARD_AIDED9
            && (board != (uint8_t)ATT_BLOCK_BOARD_GYRO3 || channels != (uint8_t)ATT_BLOCK_CH_GYR))
        || ((channels & (uint8_t)ATT_BLOCK_CH_ACC) == 0u) != (acc_every == 0u)
        || ((channels & (uint8_t)ATT_BLOCK_CH_MAG) == 0u) != (mag_every == 0u)) {
        return ATT_BLOCK_E_FIELD;
    }
    *blk++ = (uint8_t)ATT_BLOCK_MARK;
    *blk++ = (uint8_t)ATT_BLOCK_CHANNELS;
    *blk++ = board;
    *blk++ = channels;
    *blk++ = acc_every;
    *blk = mag_every;
    return ATT_OK;
}
