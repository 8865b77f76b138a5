/*
 * libattitude — block format encoders (see attitude/block.h): what the
 * AT89S51 firmware links, nothing else (the decoder and the sequence
 * tracker are in block_decode.c, because SDCC links whole modules).
 *
 * Portable C99 that SDCC compiles for the 8051 small model: 8/16-bit
 * arithmetic, no library calls, and every function a leaf, so SDCC can
 * overlay its parameters instead of giving them RAM of their own.
 */
#include "attitude/block.h"

int att_block_encode_sample(uint8_t ATT_LINK_MEM *blk, const uint16_t ATT_LINK_MEM *codes)
{
    uint8_t i;
    uint16_t c;
    if (blk == NULL || codes == NULL) {
        return ATT_E_NULL;
    }
    /* in place when codes == blk: word i is read before its two bytes are written */
    for (i = 0; i < 3u; i++) {
        c = codes[i];
        if (c > (uint16_t)ATT_BLOCK_CODE_MAX) {
            return ATT_BLOCK_E_CODE;
        }
        *blk++ = (uint8_t)(c >> 8);
        *blk++ = (uint8_t)c;
    }
    return ATT_OK;
}

int att_block_encode_boot(uint8_t ATT_LINK_MEM *blk, uint16_t period_ticks, uint8_t baud_div)
{
    if (blk == NULL) {
        return ATT_E_NULL;
    }
    /* 1..ATT_BLOCK_PERIOD_MAX in one unsigned comparison (0 wraps to 0x7FFF),
     * the link flag aside */
    if ((uint16_t)((period_ticks - 1u) & 0x7FFFu) >= (uint16_t)ATT_BLOCK_PERIOD_MAX || baud_div == 0u) {
        return ATT_BLOCK_E_FIELD;
    }
    *blk++ = (uint8_t)ATT_BLOCK_MARK;
    *blk++ = (uint8_t)ATT_BLOCK_BOOT;
    *blk++ = (uint8_t)ATT_BLOCK_VERSION;
    *blk++ = (uint8_t)(period_ticks >> 8);
    *blk++ = (uint8_t)period_ticks;
    *blk = baud_div;
    return ATT_OK;
}

int att_block_encode_selftest(uint8_t ATT_LINK_MEM *blk, int8_t status, uint16_t bad_code, uint8_t attempt)
{
    if (blk == NULL) {
        return ATT_E_NULL;
    }
    if (status >= 0 || bad_code > (uint16_t)ATT_BLOCK_CODE_MAX) {
        return ATT_BLOCK_E_FIELD;
    }
    *blk++ = (uint8_t)ATT_BLOCK_MARK;
    *blk++ = (uint8_t)ATT_BLOCK_SELFTEST;
    *blk++ = (uint8_t)status;
    *blk++ = (uint8_t)(bad_code >> 8);
    *blk++ = (uint8_t)bad_code;
    *blk = attempt;
    return ATT_OK;
}

int att_block_encode_loss(uint8_t ATT_LINK_MEM *blk, uint8_t kind, uint16_t first, uint16_t count)
{
    if (blk == NULL) {
        return ATT_E_NULL;
    }
    if (kind != (uint8_t)ATT_BLOCK_GAVE_UP && kind != (uint8_t)ATT_BLOCK_OVERRUN) {
        return ATT_BLOCK_E_KIND;
    }
    if (count == 0u) {
        return ATT_BLOCK_E_FIELD;
    }
    *blk++ = (uint8_t)ATT_BLOCK_MARK;
    *blk++ = kind;
    *blk++ = (uint8_t)(first >> 8);
    *blk++ = (uint8_t)first;
    *blk++ = (uint8_t)(count >> 8);
    *blk = (uint8_t)count;
    return ATT_OK;
}

int att_block_encode_adc_error(uint8_t ATT_LINK_MEM *blk, uint16_t first, int8_t status)
{
    if (blk == NULL) {
        return ATT_E_NULL;
    }
    if (status >= 0) {
        return ATT_BLOCK_E_FIELD;
    }
    *blk++ = (uint8_t)ATT_BLOCK_MARK;
    *blk++ = (uint8_t)ATT_BLOCK_ADC_ERROR;
    *blk++ = (uint8_t)(first >> 8);
    *blk++ = (uint8_t)first;
    *blk++ = (uint8_t)status;
    *blk = 0u;
    return ATT_OK;
}
