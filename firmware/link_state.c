/*
 * firmware/link_state.c — the link sender's state (24 bytes), alone in its
 * translation unit: SDCC allocates each module's variables as one block,
 * and a 24-byte block fills the RAM between register bank 0 and the
 * bit-addressable area (0x08-0x1F) exactly, so the rest packs without a gap.
 */
#include "attitude/link.h"

att_link_sender fw_tx;
