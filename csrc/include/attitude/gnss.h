/*
 * libattitude — GNSS receiver input: NMEA 0183 and UBX NAV-PVT parser
 * (issue 30; docs/gnss.md "Parser").
 *
 * A byte-driven state machine in the link's style (attitude/link.h): the
 * caller feeds every byte the receiver sent, one at a time, to
 * att_gnss_feed(); when a byte completes a fix, the call returns
 * ATT_GNSS_FIX and fills the caller's att_gnss_fix. No malloc, no I/O, no
 * locale, no libc number parsing (decimal fields are read with integer
 * arithmetic), no global state: everything lives in the caller-owned
 * att_gnss_parser. NMEA and UBX may be interleaved on one stream.
 *
 * NMEA 0183: $ttRMC, $ttVTG, $ttGGA and $ttGSA for any two-letter talker
 * tt (GP, GN, GL, GA, GB...). A sentence is accepted only with its "*hh"
 * checksum (XOR of the characters between '$' and '*') correct; it is
 * complete at its second checksum digit (the CR LF that follows is not
 * waited for). At most ATT_GNSS_NMEA_MAX characters from '$' to LF
 * (NMEA 0183's 82): longer is an overrun, the sentence is dropped and
 * counted. A '$' inside a sentence starts a new one (the first is counted
 * as truncated); a byte outside 0x20..0x7E inside a sentence drops it
 * (counted) and is then taken as the first byte of what follows (so a
 * UBX sync right after a cut sentence is not lost). Other sentence types
 * (GSV, GLL, ...) with a correct checksum are counted as ignored. Empty
 * fields leave their quantity absent (its ATT_GNSS_HAS_ bit clear).
 *
 * Epoch rule (NMEA): sentences are merged into one fix by UTC time. RMC
 * and GGA carry the time of their fix: a timed sentence whose time
 * differs from the fix being merged closes that fix (feed returns it) and
 * starts the next one; VTG and GSA carry no time and join the fix being
 * merged (the receiver's order within an epoch, RMC or GGA first, is that
 * of u-blox, SiRF, MediaTek...). A fix is therefore reported when the
 * next epoch's first timed sentence arrives, or at once by
 * att_gnss_flush() (the end of a log, or a caller that knows its
 * receiver's last sentence). A quantity given by two sentences of one
 * epoch (position in RMC and GGA) takes the later one.
 *
 * UBX: sync 0xB5 0x62, class, id, little-endian length, payload, the
 * 8-bit Fletcher checksum over class..payload. NAV-PVT (class 0x01, id
 * 0x07, 92 bytes; u-blox M8/M9 interface description) is a whole fix and
 * is reported when its checksum byte arrives, independently of any NMEA
 * fix being merged. Other messages are skipped by their length (checksum
 * still verified, counted as ignored); a length above
 * ATT_GNSS_UBX_SKIP_MAX is taken for garbage (counted as an overrun) and
 * the parser goes back to hunting right after the length field, so any
 * garbage costs at most that many bytes before sync is found again.
 *
 * Errors in the stream are counted (att_gnss_stats) and reported by the
 * return value of the byte that revealed them; they never produce a fix.
 */
#ifndef ATTITUDE_GNSS_H
#define ATTITUDE_GNSS_H

#include "attitude/common.h"

ATT_API_BEGIN

/* Limits and protocol constants. */
enum {
    ATT_GNSS_NMEA_MAX = 82,       /* characters of a sentence, '$' to LF inclusive (NMEA 0183) */
    ATT_GNSS_NMEA_BODY = 76,      /* characters between '$' and '*': 82 - "$" - "*hh" - CR LF */
    ATT_GNSS_UBX_SYNC1 = 0xB5,    /* UBX frame's first sync byte */
    ATT_GNSS_UBX_SYNC2 = 0x62,    /* UBX frame's second sync byte */
    ATT_GNSS_UBX_NAV = 0x01,      /* UBX class NAV */
    ATT_GNSS_UBX_PVT = 0x07,      /* UBX id of NAV-PVT */
    ATT_GNSS_UBX_PVT_LEN = 92,    /* NAV-PVT payload length (bytes) */
    ATT_GNSS_UBX_SKIP_MAX = 1024, /* longest UBX payload skipped; longer lengths are garbage */
    ATT_GNSS_MAX_SATS = 255       /* satellites used: 0..255 */
};

/* What one att_gnss_feed() or att_gnss_flush() call did. Negative: an error. */
typedef enum {
    ATT_GNSS_NONE = 0,      /* byte taken, nothing completed (or flush: no fix was being merged) */
    ATT_GNSS_FIX = 1,       /* *out holds a complete fix */
    ATT_GNSS_MESSAGE = 2,   /* a sentence / NAV-PVT was accepted and merged, no fix completed yet */
    ATT_GNSS_IGNORED = 3,   /* a well-formed sentence or UBX message of another type, skipped */
    ATT_GNSS_REJECTED = 4,  /* a sentence / frame dropped: bad checksum, overrun, cut, bad field */
    ATT_GNSS_E_NULL = -220, /* a required pointer is NULL */
    ATT_GNSS_E_STATE = -221 /* internal state corrupted (struct overwritten?) */
} att_gnss_result;

/* The parser is not built for the 8051 (its state alone exceeds the AT89S51's
 * 256 bytes of RAM, and SDCC's 16-bit int cannot hold the presence bits):
 * there, only the status codes above are visible (csrc/src/common.c's table). */
#if !defined(__SDCC)

/* Fix type (att_gnss_fix.fix_type): NAV-PVT's fixType values. NMEA: GSA's
 * mode 1 / 2 / 3 -> NONE / 2D / 3D; GGA's quality 0 -> NONE, 6 -> DR. */
typedef enum {
    ATT_GNSS_FIX_NONE = 0,    /* no fix */
    ATT_GNSS_FIX_DR = 1,      /* dead reckoning only */
    ATT_GNSS_FIX_2D = 2,      /* 2D fix (height not solved) */
    ATT_GNSS_FIX_3D = 3,      /* 3D fix */
    ATT_GNSS_FIX_GNSS_DR = 4, /* GNSS combined with dead reckoning */
    ATT_GNSS_FIX_TIME = 5     /* time only */
} att_gnss_fix_type;

/* Which fields of att_gnss_fix hold a value (bits of att_gnss_fix.present).
 * A clear bit: the receiver did not give that quantity in this epoch (an
 * empty field, a sentence not sent); the field then holds 0. */
enum {
    ATT_GNSS_HAS_TOD = 1 << 0,        /* tod (UTC time of day) */
    ATT_GNSS_HAS_DATE = 1 << 1,       /* year, month, day */
    ATT_GNSS_HAS_TOW = 1 << 2,        /* tow (GPS time of week; NAV-PVT only) */
    ATT_GNSS_HAS_FIX_TYPE = 1 << 3,   /* fix_type */
    ATT_GNSS_HAS_VALID = 1 << 4,      /* valid */
    ATT_GNSS_HAS_LATLON = 1 << 5,     /* lat, lon */
    ATT_GNSS_HAS_HEIGHT = 1 << 6,     /* height (above the ellipsoid) */
    ATT_GNSS_HAS_HEIGHT_MSL = 1 << 7, /* height_msl (above mean sea level) */
    ATT_GNSS_HAS_VEL_NE = 1 << 8,     /* vel_n, vel_e */
    ATT_GNSS_HAS_VEL_D = 1 << 9,      /* vel_d (NAV-PVT only: NMEA has no vertical velocity) */
    ATT_GNSS_HAS_SPEED = 1 << 10,     /* speed */
    ATT_GNSS_HAS_TRACK = 1 << 11,     /* track */
    ATT_GNSS_HAS_HDOP = 1 << 12,      /* hdop (GGA, GSA) */
    ATT_GNSS_HAS_PDOP = 1 << 13,      /* pdop (GSA, NAV-PVT) */
    ATT_GNSS_HAS_VDOP = 1 << 14,      /* vdop (GSA) */
    ATT_GNSS_HAS_SATS = 1 << 15,      /* sats (GGA, NAV-PVT) */
    ATT_GNSS_HAS_ACC = 1 << 16        /* h_acc, v_acc, s_acc (NAV-PVT only) */
};

/* Which messages a fix was merged from (bits of att_gnss_fix.sources). */
enum {
    ATT_GNSS_SRC_RMC = 1 << 0,
    ATT_GNSS_SRC_VTG = 1 << 1,
    ATT_GNSS_SRC_GGA = 1 << 2,
    ATT_GNSS_SRC_GSA = 1 << 3,
    ATT_GNSS_SRC_PVT = 1 << 4
};

/* One fix: one epoch of the receiver. Angles in radians, lengths in
 * metres, speeds in m/s, times in seconds; a field is meaningful only
 * when its ATT_GNSS_HAS_ bit is set in `present`, else it is 0. */
typedef struct {
    att_real tod;        /* s, UTC time of day 0 <= tod < 86401 (leap second: sec 60) */
    att_real tow;        /* s, GPS time of week 0 <= tow < 604800 (NAV-PVT iTOW) */
    att_real lat;        /* rad, geodetic latitude, -pi/2..pi/2, north positive */
    att_real lon;        /* rad, longitude, -pi..pi, east positive */
    att_real height;     /* m, height above the WGS84 ellipsoid (NAV-PVT height; GGA altitude +
                            geoid separation) */
    att_real height_msl; /* m, height above mean sea level (NAV-PVT hMSL; GGA altitude) */
    att_real vel_n;      /* m/s, velocity north (NAV-PVT velN; NMEA: speed * cos(track)) */
    att_real vel_e;      /* m/s, velocity east (NAV-PVT velE; NMEA: speed * sin(track)) */
    att_real vel_d;      /* m/s, velocity down (NAV-PVT velD only) */
    att_real speed;      /* m/s, ground speed >= 0 (NAV-PVT gSpeed; RMC / VTG knots or km/h) */
    att_real track;      /* rad, course over ground from true north, clockwise, 0..2pi
                            (NAV-PVT headMot; RMC / VTG true course) */
    att_real hdop;       /* horizontal dilution of precision (dimensionless, >= 0) */
    att_real pdop;       /* position dilution of precision (dimensionless, >= 0) */
    att_real vdop;       /* vertical dilution of precision (dimensionless, >= 0) */
    att_real h_acc;      /* m, receiver's horizontal accuracy estimate (NAV-PVT hAcc) */
    att_real v_acc;      /* m, receiver's vertical accuracy estimate (NAV-PVT vAcc) */
    att_real s_acc;      /* m/s, receiver's speed accuracy estimate (NAV-PVT sAcc) */
    uint32_t present;    /* ATT_GNSS_HAS_* bits: which fields hold a value */
    uint16_t year;       /* UTC date: year (4 digits; RMC's yy: 80..99 -> 19yy, else 20yy) */
    uint8_t month;       /* 1..12 */
    uint8_t day;         /* 1..31 */
    uint8_t fix_type;    /* att_gnss_fix_type */
    uint8_t valid;       /* 1: the receiver flags the fix valid (RMC status A, GGA quality > 0,
                            NAV-PVT gnssFixOK); 0: it flags it invalid. Merged: 0 if any
                            sentence of the epoch said invalid */
    uint8_t sats;        /* satellites used in the solution, 0..255 */
    uint8_t sources;     /* ATT_GNSS_SRC_* bits: the messages merged into this fix */
} att_gnss_fix;

/* Counters since init (wrap modulo 2^32). */
typedef struct {
    uint32_t bytes;         /* bytes fed */
    uint32_t nmea_accepted; /* RMC / VTG / GGA / GSA sentences merged into a fix */
    uint32_t ubx_accepted;  /* NAV-PVT messages reported as fixes */
    uint32_t fixes;         /* fixes reported (feed and flush) */
    uint32_t ignored;       /* well-formed sentences / UBX messages of other types */
    uint32_t bad_checksum;  /* NMEA or UBX checksum mismatch */
    uint32_t overruns;      /* sentence longer than ATT_GNSS_NMEA_MAX, UBX length over
                                ATT_GNSS_UBX_SKIP_MAX or NAV-PVT of the wrong length */
    uint32_t truncated;     /* sentence cut by a '$', a CR / LF or a non-printable byte */
    uint32_t bad_field;     /* accepted checksum but a field that does not parse */
    uint32_t bytes_skipped; /* bytes outside any sentence or frame (not CR / LF) */
} att_gnss_stats;

/* The parser: caller-owned, set up by att_gnss_init; fields are private
 * except stats (read them freely). */
typedef struct {
    att_gnss_stats stats;
    att_gnss_fix epoch;                /* NMEA fix being merged (epoch_open) */
    uint8_t buf[ATT_GNSS_UBX_PVT_LEN]; /* NMEA body or NAV-PVT payload */
    uint16_t len;                      /* bytes in buf / payload bytes seen */
    uint16_t ubx_len;                  /* UBX payload length */
    uint8_t state;                     /* private state (enum in gnss_parse.c) */
    uint8_t sum;                       /* NMEA XOR / UBX Fletcher A */
    uint8_t sum_b;                     /* UBX Fletcher B; NMEA: first checksum digit */
    uint8_t ubx_class;                 /* UBX class of the frame in progress */
    uint8_t ubx_id;                    /* UBX id of the frame in progress */
    uint8_t epoch_open;                /* bit 0: `epoch` holds merged sentences; bit 1: and
                                           its UTC time is epoch_sec + epoch_ns */
    uint32_t epoch_sec;                /* the merged epoch's hhmmss (as written) */
    uint32_t epoch_ns;                 /* the merged epoch's fraction of a second (ns) */
} att_gnss_parser;

/* Zero the statistics, drop any partial message and merged epoch, hunt.
 * ATT_OK or ATT_GNSS_E_NULL. */
int att_gnss_init(att_gnss_parser *p);

/* Take one byte of the receiver's stream. Returns ATT_GNSS_FIX (then *out
 * is the fix), ATT_GNSS_MESSAGE, ATT_GNSS_IGNORED, ATT_GNSS_REJECTED,
 * ATT_GNSS_NONE, or ATT_GNSS_E_NULL / ATT_GNSS_E_STATE (p unchanged). *out
 * is written only with ATT_GNSS_FIX. */
att_gnss_result att_gnss_feed(att_gnss_parser *p, uint8_t byte, att_gnss_fix *out);

/* Feed n bytes of data: as att_gnss_feed for each, the fixes written to
 * fixes[0..cap-1] in order; stops early when cap fixes are written (the
 * bytes not taken are then data[*used..n-1]). *used and *n_fix are set.
 * ATT_OK, or ATT_GNSS_E_NULL (NULL p, used, n_fix; NULL data with n > 0;
 * NULL fixes with cap > 0) / ATT_GNSS_E_STATE, nothing taken. */
int att_gnss_feed_buf(att_gnss_parser *p, const uint8_t *data, size_t n, att_gnss_fix *fixes, size_t cap,
                      size_t *used, size_t *n_fix);

/* Report the NMEA fix being merged now (end of a log, or the receiver's
 * last sentence of an epoch seen): ATT_GNSS_FIX and *out, or
 * ATT_GNSS_NONE when none is open; a message in progress is kept. */
att_gnss_result att_gnss_flush(att_gnss_parser *p, att_gnss_fix *out);

#endif /* !__SDCC */

ATT_API_END

#endif /* ATTITUDE_GNSS_H */
