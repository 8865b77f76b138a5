/*
 * libattitude — GNSS parser internals shared by gnss_parse.c (framing),
 * gnss_nmea.c (sentences, epoch merging) and gnss_ubx.c (NAV-PVT).
 * Not part of the public API.
 */
#ifndef ATT_SRC_GNSS_INTERNAL_H
#define ATT_SRC_GNSS_INTERNAL_H

#include "attitude/gnss.h"

/* The parser's epoch_open bits. */
enum {
    ATT__GNSS_OPEN = 1, /* an NMEA epoch is being merged */
    ATT__GNSS_TIMED = 2 /* and it has its UTC time (epoch_sec, epoch_ns) */
};

/* A checked NMEA body (buf[0..len-1], between '$' and '*'): merge it.
 * Returns ATT_GNSS_FIX (a previous epoch closed: *out), ATT_GNSS_MESSAGE,
 * ATT_GNSS_IGNORED or ATT_GNSS_REJECTED; counts in p->stats. */
att_gnss_result att__gnss_nmea(att_gnss_parser *p, att_gnss_fix *out);

/* Complete the merged epoch into *out (derived velocity), close it. */
void att__gnss_close_epoch(att_gnss_parser *p, att_gnss_fix *out);

/* A checked NAV-PVT payload (buf, ATT_GNSS_UBX_PVT_LEN bytes) into *out:
 * ATT_GNSS_FIX, or ATT_GNSS_REJECTED for a field out of its domain. */
att_gnss_result att__gnss_nav_pvt(att_gnss_parser *p, att_gnss_fix *out);

/* Angle in degrees * 10^-k (k = 0..7) -> rad. */
att_real att__gnss_deg_to_rad(att_real deg);

/* A course in rad brought into 0 <= a < 2 pi (a in -2 pi..4 pi). */
att_real att__gnss_wrap_2pi(att_real a);

#endif /* ATT_SRC_GNSS_INTERNAL_H */
