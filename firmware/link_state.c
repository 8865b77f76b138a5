/*
 * firmware/link_state.c — the link sender's state, alone in its
 * translation unit: SDCC allocates each module's variables as one block.
 * Legacy (AA/BB) build: att_link_sender is 24 bytes, which fill the RAM
 * between register bank 0 and the bit-addressable area (0x08-0x1F)
 * exactly, so the rest packs without a gap. Link v2 build (FW_LINK_V2):
 * the single-instance sender att_link2_one (attitude/link2.h, its ring
 * included).
 */
#include "config.h"

#if FW_LINK_V2
#include "attitude/link2.h"

att_link2_sender ATT_LINK_MEM att_link2_one;
#if ATT_LINK2_ONE_RING_IDATA
uint8_t __idata att_link2_one_ring[ATT_LINK2_ONE_RING * ATT_LINK2_RECORD]; /* the aided AT89S52: upper RAM */
#endif
#else
#include "attitude/link.h"

att_link_sender fw_tx;
#endif
