/*
 * libattitude — serial link v2: a hardened, streaming protocol between the
 * acquisition board (sender A) and the Linux computer (receiver B), beside
 * the paper's AA/BB handshake (attitude/link.h, unchanged). Prefix
 * att_link2_, status codes -200..-219. Spec and justification: docs/link.md
 * ("Link v2").
 *
 * Records. What travels is a stream of block-format records
 * (attitude/block.h, ATT_LINK2_RECORD = 6 bytes each), each numbered by an
 * 8-bit record sequence number (mod 256). A sample record whose three codes
 * are 0..4095 travels packed (three 12-bit codes in 4.5 bytes, several per
 * frame); any other record (the reports, oversampled sums) travels as it is,
 * one per RAW frame. The receiver hands out 6-byte block-format records again.
 *
 * Frames (decoded bytes; multi-byte fields big-endian):
 *
 *     DATA  A->B  [0x00 | e | n] [seq] [packed codes of n samples] [crc32]
 *                 n = 0..ATT_LINK2_SAMPLES_MAX; n = 0 is a probe (no data)
 *     RAW   A->B  [0x40 | e] [seq] [6-byte record] [crc32]
 *     SYN   A->B  [0x80] [seq]                 [crc32]   session start at seq
 *     ACK   B->A  [0xC0 | flags] [ack] [limit] [crc32]
 *
 *   packed codes: the 3n codes c0, c1, ... (sample 0 X, Y, Z, sample 1 X,
 *   ...) two by two in 3 bytes: c0 >> 4, (c0 & 15) << 4 | c1 >> 8, c1 & 255;
 *   an odd last code takes 2 bytes, the last 4 bits 0: (9n + 1) / 2 bytes.
 *   crc32: CRC-32C (Castagnoli: poly 0x1EDC6F41 reflected, init and final
 *   xor 0xFFFFFFFF; check value of "123456789" 0xE3069283) of every byte
 *   before it, most significant byte first. Hamming distance 6 for frames
 *   of 178..5243 data bits (every frame here: 32..880 bits; 8 below 178):
 *   every error of up to 5 bits is detected, and random garbage passes
 *   with probability 2^-32 (docs/link.md: why not a CRC-16, and where the
 *   figures come from).
 *   ack: the seq of the next record B expects (every record before it is
 *   delivered); limit: B takes records with seq < limit (mod 256, limit -
 *   ack <= 127): its free room, the back-pressure. flags: ATT_LINK2_F_GAP
 *   (the frame answered started after ack: something was lost),
 *   ATT_LINK2_F_SYNACK (answers a SYN), ATT_LINK2_F_NOSESSION (B has no
 *   session: A must send SYN first), ATT_LINK2_F_EPOCH (echoes e).
 *   e (0x20): the sender's epoch bit, toggled at each go-back; B echoes the
 *   e of the frame it answers, so A tells a GAP report about what it sent
 *   after its last go-back from a stale one.
 *
 * Wire encoding: each frame is rCOBS-encoded (reverse consistent-overhead
 * byte stuffing: every 0x00 of the frame is replaced by 1 + the number of
 * bytes since the previous code, a code 0xFF stands after 254 bytes without
 * a zero, a final code 1 + the bytes since the last code ends the frame)
 * and followed by the delimiter 0x00, so 0x00 never occurs inside a frame:
 * a receiver resynchronizes at the next 0x00 whatever garbage came before.
 * The encoder streams (no look-ahead: what the 8051 needs), the decoder
 * works backwards from the delimiter. A sender whose line was idle puts a
 * 0x00 before the frame too, so noise on an idle line costs no frame.
 * Overhead: 2 bytes per frame (code + delimiter) for frames < 254 bytes.
 *
 * Protocol: A numbers records, streams frames while their records are below
 * B's limit and inside its ring (the window), and keeps every record until
 * an ACK covers it. B delivers records in order, exactly once: a frame that
 * starts at or before `ack` delivers its new records (as many as B has room
 * for), records before `ack` are duplicates and dropped, a frame starting
 * after `ack` is dropped and answered with F_GAP. B answers every valid
 * frame with an ACK. A goes back to the first unacknowledged record (go-back-N
 * at record granularity: the records after a lost one were refused by B, so
 * what is resent is what B lost) on an F_GAP answering a frame of its current epoch, or when `rto`
 * ticks pass without progress while records are unacknowledged; it probes
 * with an empty DATA frame when B's limit blocks it for `rto` ticks. A
 * session starts with SYN (at power-up, and when B answers F_NOSESSION: B
 * rebooted) and A sends data only after its SYNACK, so a new session never
 * meets stale data. acknowledged => delivered: B advances `ack` only over
 * records it handed to its caller.
 *
 * Ticks (sender only): a free-running 16-bit counter in the caller's unit,
 * wrap-safe; the timer expires when more than `rto` ticks have elapsed;
 * rto is 1..32767 and poll must run at least every 32768 ticks.
 *
 * The sender (link2_sender.c) compiles for the AT89S51 with SDCC (small
 * model, ATT_LINK_MEM pointers, 8/16-bit arithmetic, no library calls);
 * the receiver (link2_receiver.c) is for the Linux side (about 450 bytes of
 * state).
 */
#ifndef ATTITUDE_LINK2_H
#define ATTITUDE_LINK2_H

#include "attitude/common.h"
#include "attitude/link.h" /* ATT_LINK_MEM */

ATT_API_BEGIN

/* Protocol constants. */
enum {
    ATT_LINK2_DELIM = 0x00,     /* frame delimiter on the wire */
    ATT_LINK2_RECORD = 6,       /* bytes of one record (ATT_BLOCK_SIZE) */
    ATT_LINK2_SAMPLES_MAX = 24, /* samples in one DATA frame (protocol limit) */
    ATT_LINK2_SAMPLES_DEFAULT =
        16, /* sender default: 82 bytes on the wire per frame, 187 samples/s at 9600 baud */
    ATT_LINK2_FRAME_MAX = 114,  /* decoded bytes of the longest frame: 2 + 108 + 4 */
    ATT_LINK2_WIRE_MAX = 115,   /* encoded bytes of the longest frame before its delimiter */
    ATT_LINK2_OUT_MAX = 144,    /* bytes of the receiver's output buffer: 24 records */
    ATT_LINK2_RING_MAX = 64,    /* largest sender ring (records, a power of two) */
    ATT_LINK2_WINDOW_MAX = 127, /* largest limit - ack (half the sequence space) */
    ATT_LINK2_T_DATA = 0x00,    /* frame types: byte 0 & 0xC0 */
    ATT_LINK2_T_RAW = 0x40,
    ATT_LINK2_T_SYN = 0x80,
    ATT_LINK2_T_ACK = 0xC0,
    ATT_LINK2_F_GAP = 0x01, /* ACK flags: byte 0 & 0x0F */
    ATT_LINK2_F_SYNACK = 0x02,
    ATT_LINK2_F_NOSESSION = 0x04,
    ATT_LINK2_F_EPOCH = 0x08,      /* the e bit of the frame answered */
    ATT_LINK2_E_BIT = 0x20,        /* DATA, RAW: the epoch bit */
    ATT_LINK2_TIMEOUT_MAX = 32767, /* largest rto (ticks) */
    ATT_LINK2_NO_TIMER = 0xFFFF    /* ticks_left(): no timer running */
};

/* What one sink or poll call did. Negative values are errors. */
typedef enum {
    ATT_LINK2_NONE = 0,        /* sink: byte stored, frame incomplete / poll: nothing to send now */
    ATT_LINK2_IDLE = 1,        /* poll: nothing to send and nothing awaited (sender: all acknowledged) */
    ATT_LINK2_SEND = 2,        /* poll: *out_byte is the next byte to transmit */
    ATT_LINK2_FRAME = 3,       /* sink: a valid frame ended here (nothing delivered) / sender: an ACK */
    ATT_LINK2_DELIVERED = 4,   /* sink (receiver): r->n_out new records are in the output buffer */
    ATT_LINK2_BAD_FRAME = 5,   /* sink: a frame ended here that fails its CRC, encoding or format: dropped */
    ATT_LINK2_DISCARDED = 6,   /* sink: byte dropped (inside an over-long frame) */
    ATT_LINK2_TIMEOUT = 7,     /* poll (sender): the timer expired: going back / re-SYN / probing */
    ATT_LINK2_E_NULL = -200,   /* a required pointer is NULL */
    ATT_LINK2_E_CONFIG = -201, /* configuration out of range */
    ATT_LINK2_E_FULL = -202,   /* sender push: the ring is full (wait for acknowledgements) */
    ATT_LINK2_E_STATE = -203   /* internal state corrupted (struct overwritten?) */
} att_link2_result;

/* ------------------------------------------------------------------ */
/* Sender A                                                           */
/* ------------------------------------------------------------------ */

typedef struct {
    uint16_t rto;        /* ticks without progress before A goes back, re-SYNs or probes (1..32767) */
    uint8_t max_samples; /* samples per DATA frame, 1..ATT_LINK2_SAMPLES_MAX */
    uint8_t ring_size;   /* records the caller's ring holds: 1, 2, 4, .., 64 (the window) */
} att_link2_sender_config;

/* Counters wrap modulo 2^16 (8051 RAM). */
typedef struct {
    uint16_t frames;     /* frames sent (every kind) */
    uint16_t records;    /* records sent for the first time */
    uint16_t resent;     /* records sent again */
    uint16_t acks;       /* valid ACK frames received */
    uint16_t bad_frames; /* received frames dropped (CRC, encoding, format, stale ack) */
    uint16_t timeouts;   /* timer expiries (go-back, SYN again, probe) */
    uint16_t gobacks;    /* go-backs on F_GAP */
    uint16_t syns;       /* SYN frames sent */
} att_link2_sender_stats;

/* Single-instance build for the AT89S51 (ATT_LINK2_ONE = 1, set by the
 * firmware's build: docs/link.md "On the AT89S51"). The same source
 * compiles to a sender whose state is one object the firmware defines,
 * `att_link2_sender att_link2_one` (in internal RAM, reached by direct
 * addressing: no pointer), whose configuration is fixed at compile time
 * (ATT_LINK2_ONE_RTO ticks, ATT_LINK2_ONE_SAMPLES per frame, a ring of
 * ATT_LINK2_ONE_RING records inside the state), and which keeps no
 * statistics. The functions below keep their names and arguments (macros
 * drop s, cfg and ring); att_link2_sender_init returns nothing, and
 * config_init, ticks_left and att_link2_crc do not exist in this build.
 * The wire protocol is the same. */
#ifndef ATT_LINK2_ONE
#define ATT_LINK2_ONE 0
#endif
/* ATT_LINK2_CRC_TABLE = 1 (8051 only, for an image with 1 KB of flash to
 * spare: the aided AT89S52 firmware): att_link2_crc_byte looks its byte up
 * in a 256-entry table the firmware links (att_link2_crc_t0..t3, four byte
 * planes in code memory) instead of the bitwise loop: about 45 machine
 * cycles per byte instead of 230. Same CRC, same wire. */
#ifndef ATT_LINK2_CRC_TABLE
#define ATT_LINK2_CRC_TABLE 0
#endif
/* ATT_LINK2_CURSOR = 1 (the default: the library, the aided AT89S52
 * image): the packed codes of a DATA frame are read through a cursor that
 * walks the ring (f_ptr, one or two bytes per frame byte, three frame
 * bytes per pair of codes: f_ph, f_nib): in s51 a poll that sends a byte
 * costs about 220 machine cycles instead of 340; 0 (the AT89S51 v2 image,
 * which toolchain/firmware.py keeps byte for byte as it was): each frame
 * byte is recomputed from its index (two nibbles, a division by 9 each).
 * Same wire. */
#ifndef ATT_LINK2_CURSOR
#define ATT_LINK2_CURSOR 1
#endif
#if ATT_LINK2_ONE
#ifndef ATT_LINK2_ONE_RTO
#define ATT_LINK2_ONE_RTO 720 /* ticks: 200 ms of the firmware's 1/3600 s ticks */
#endif
#ifndef ATT_LINK2_ONE_SAMPLES
#define ATT_LINK2_ONE_SAMPLES 4 /* samples per DATA frame */
#endif
#ifndef ATT_LINK2_ONE_RING
#define ATT_LINK2_ONE_RING 4 /* records: 1, 2, 4, .., 64 */
#endif
/* ATT_LINK2_ONE_RING_IDATA = 1 (an 8052: 256 bytes of RAM): the ring is
 * not inside att_link2_one but the firmware's own array
 * `uint8_t __idata att_link2_one_ring[ATT_LINK2_ONE_RING * 6]`, which the
 * linker may place in the upper 128 bytes (reached only through @R0/@R1,
 * as the sender reaches the ring anyway): a longer ring than direct RAM
 * holds, hence longer frames and fewer ACKs per record. */
#ifndef ATT_LINK2_ONE_RING_IDATA
#define ATT_LINK2_ONE_RING_IDATA 0
#endif
/* Batching (0 = off: a DATA frame starts as soon as a record is ready):
 * between frames the sender holds back a DATA frame while fewer than
 * ATT_LINK2_ONE_BATCH records are ready to send and at most
 * ATT_LINK2_ONE_HOLD ticks have passed since its last progress (frame end,
 * ACK): a board that pushes records faster than its CPU can frame them one
 * sample at a time sends fewer, longer frames (the per-frame cost: 8 bytes
 * of header, CRC and delimiters, an ACK of 9 bytes to receive and check),
 * for a latency of at most ATT_LINK2_ONE_HOLD ticks. */
#ifndef ATT_LINK2_ONE_BATCH
#define ATT_LINK2_ONE_BATCH 0
#endif
#ifndef ATT_LINK2_ONE_HOLD
#define ATT_LINK2_ONE_HOLD 0
#endif
#if ATT_LINK2_ONE_BATCH < 0 || ATT_LINK2_ONE_BATCH > ATT_LINK2_ONE_RING || ATT_LINK2_ONE_HOLD < 0 \
    || ATT_LINK2_ONE_HOLD > 32767
#error "ATT_LINK2_ONE_BATCH must be 0..ATT_LINK2_ONE_RING, ATT_LINK2_ONE_HOLD 0..32767 ticks"
#endif
#if ATT_LINK2_ONE_RTO < 1 || ATT_LINK2_ONE_RTO > 32767 || ATT_LINK2_ONE_SAMPLES < 1    \
    || ATT_LINK2_ONE_SAMPLES > 24 || ATT_LINK2_ONE_RING < 1 || ATT_LINK2_ONE_RING > 64 \
    || (ATT_LINK2_ONE_RING & (ATT_LINK2_ONE_RING - 1)) != 0
#error \
    "ATT_LINK2_ONE_RTO must be 1..32767, ATT_LINK2_ONE_SAMPLES 1..24, ATT_LINK2_ONE_RING a power of two <= 64"
#endif
#endif

typedef struct {
#if !ATT_LINK2_ONE
    att_link2_sender_config cfg;
    att_link2_sender_stats stats;
    uint8_t ATT_LINK_MEM *ring; /* caller's ring: cfg.ring_size records of 6 bytes */
#endif
    uint16_t t0;     /* tick of the last progress (frame end, ack, go-back) */
    uint32_t crc;    /* CRC of the frame being sent (running, not yet inverted) */
    uint8_t head;    /* seq of the next record pushed */
    uint8_t base;    /* seq of the oldest unacknowledged record */
    uint8_t next;    /* seq of the next record to send */
    uint8_t hi;      /* one past the highest seq sent */
    uint8_t limit;   /* B's limit */
    uint8_t session; /* private: SYN needed / SYN sent / running */
    uint8_t tx;      /* private: emitter state (one function per state) */
    uint8_t flags;   /* private: line idle, epoch */
    uint8_t f_head;  /* frame being sent: byte 0 */
    uint8_t f_seq;   /*   its seq */
    uint8_t f_len;   /*   decoded length including the CRC */
    uint8_t f_pos;   /*   next decoded byte */
    uint8_t run;     /*   rCOBS: bytes since the last code */
    uint8_t rx_len;  /* ACK bytes received so far (0xFF: skipping an over-long frame) */
#if ATT_LINK2_CURSOR
    uint8_t ATT_LINK_MEM *f_ptr; /* frame being sent: the ring byte its next data byte reads */
    uint8_t f_ph;                /*   packed codes: byte 0, 1 or 2 of a pair of codes */
    uint8_t f_nib;               /*   the pair's first code's low nibble (<< 4) for byte 1 */
#endif
#if !ATT_LINK2_ONE
    uint8_t cur; /* samples per frame now: halved on a loss, +1 per progress */
#endif
    uint8_t rx[8]; /* encoded ACK frame being received */
#if ATT_LINK2_ONE && !ATT_LINK2_ONE_RING_IDATA
    uint8_t ring[ATT_LINK2_ONE_RING * ATT_LINK2_RECORD]; /* the ring (single-instance build) */
#endif
} att_link2_sender;

#if ATT_LINK2_ONE
extern att_link2_sender ATT_LINK_MEM att_link2_one; /* defined by the firmware */
#if ATT_LINK2_ONE_RING_IDATA
extern uint8_t __idata att_link2_one_ring[ATT_LINK2_ONE_RING * ATT_LINK2_RECORD]; /* ... and its ring */
#endif
void att_link2_sender1_init(void);
void att_link2_sender1_reset(void);
uint8_t att_link2_sender1_room(void);
uint8_t att_link2_sender1_pending(void);
int att_link2_sender1_push(const uint8_t ATT_LINK_MEM *record);
uint8_t ATT_LINK_MEM *att_link2_sender1_tail(void);
att_link2_result att_link2_sender1_sink(uint8_t byte, uint16_t tick);
att_link2_result att_link2_sender1_poll(uint16_t tick, uint8_t ATT_LINK_MEM *out_byte);
#define att_link2_sender_init(s, cfg, ring)      att_link2_sender1_init()
#define att_link2_sender_reset(s)                att_link2_sender1_reset()
#define att_link2_sender_room(s)                 att_link2_sender1_room()
#define att_link2_sender_pending(s)              att_link2_sender1_pending()
#define att_link2_sender_push(s, record)         att_link2_sender1_push(record)
#define att_link2_sender_tail(s)                 att_link2_sender1_tail()
#define att_link2_sender_sink(s, byte, tick)     att_link2_sender1_sink(byte, tick)
#define att_link2_sender_poll(s, tick, out_byte) att_link2_sender1_poll(tick, out_byte)
#else

/* (link2_sender_aux.c) Defaults for 1 ms ticks at 9600 baud: rto 200 ms
 * (a full 16-sample frame is 82 bytes on the wire, 85 ms; its ACK 10 bytes,
 * 10 ms; the rest is the receiver's latency), 16 samples per frame,
 * ring_size as given. Scale rto for other tick units and baud rates. */
void att_link2_sender_config_init(att_link2_sender_config *cfg, uint8_t ring_size);

/* Check cfg, attach `ring` (cfg->ring_size * 6 bytes, caller-owned), zero
 * the statistics, start a new session (SYN at seq 0). ATT_OK,
 * ATT_LINK2_E_NULL or ATT_LINK2_E_CONFIG (then every call fails). */
int att_link2_sender_init(att_link2_sender ATT_LINK_MEM *s, const att_link2_sender_config *cfg,
                          uint8_t ATT_LINK_MEM *ring);

/* New session (SYN at seq 0) with an empty ring, statistics kept: what a
 * rebooted board does. Records not yet acknowledged are dropped. */
void att_link2_sender_reset(att_link2_sender ATT_LINK_MEM *s);

/* Records the ring can take now (0..ring_size). */
uint8_t att_link2_sender_room(const att_link2_sender ATT_LINK_MEM *s);

/* Records pushed and not yet acknowledged (0..ring_size). */
uint8_t att_link2_sender_pending(const att_link2_sender ATT_LINK_MEM *s);

/* Copy one 6-byte block-format record into the ring: ATT_OK,
 * ATT_LINK2_E_NULL, ATT_LINK2_E_FULL or ATT_LINK2_E_STATE. */
int att_link2_sender_push(att_link2_sender ATT_LINK_MEM *s, const uint8_t ATT_LINK_MEM *record);

/* The ring slot the next push fills (6 bytes), or NULL if the ring is
 * full (or s is NULL or unusable): a caller may build the record there and
 * push that pointer (push then copies nothing new), which saves a record
 * buffer on the 8051. The slot is the caller's until that push. */
uint8_t ATT_LINK_MEM *att_link2_sender_tail(att_link2_sender ATT_LINK_MEM *s);

/* A byte arrived from B: ATT_LINK2_NONE (stored), ATT_LINK2_FRAME (a valid
 * ACK was applied), ATT_LINK2_BAD_FRAME, ATT_LINK2_DISCARDED, or an error. */
att_link2_result att_link2_sender_sink(att_link2_sender ATT_LINK_MEM *s, uint8_t byte, uint16_t tick);

/* Advance at `tick` (call when the transmitter can take a byte):
 * ATT_LINK2_SEND (*out_byte), ATT_LINK2_TIMEOUT (call again), ATT_LINK2_NONE
 * (waiting for B or for records below B's limit), ATT_LINK2_IDLE (every
 * record acknowledged, nothing to send) or an error. */
att_link2_result att_link2_sender_poll(att_link2_sender ATT_LINK_MEM *s, uint16_t tick,
                                       uint8_t ATT_LINK_MEM *out_byte);

/* Ticks after `now` at which poll acts on the timer (0: now),
 * ATT_LINK2_NO_TIMER if none runs. (link2_sender_aux.c) */
uint16_t att_link2_sender_ticks_left(const att_link2_sender *s, uint16_t now);
#endif /* ATT_LINK2_ONE */

/* ------------------------------------------------------------------ */
/* Receiver B                                                         */
/* ------------------------------------------------------------------ */

typedef struct {
    uint32_t frames;          /* valid frames received (every kind) */
    uint32_t bad_frames;      /* frames dropped: CRC, encoding, length or type wrong */
    uint32_t records;         /* records delivered to the caller */
    uint32_t duplicates;      /* records received again after delivery: dropped */
    uint32_t gaps;            /* frames that started after ack (answered F_GAP) */
    uint32_t refused;         /* new records not taken for lack of room (back-pressure) */
    uint32_t syns;            /* SYN frames received (sessions started) */
    uint32_t no_session;      /* data frames received before any SYN */
    uint32_t acks;            /* ACK frames sent */
    uint32_t bytes_discarded; /* bytes of over-long frames */
} att_link2_receiver_stats;

typedef struct {
    att_link2_receiver_stats stats;
    uint8_t *out;                    /* caller's buffer, ATT_LINK2_OUT_MAX bytes */
    uint16_t room;                   /* records the caller can take now */
    uint8_t n_out;                   /* records in out after ATT_LINK2_DELIVERED */
    uint8_t synced;                  /* a session is running */
    uint8_t expected;                /* ack: seq of the next record to deliver */
    uint8_t last_limit;              /* limit of the last ACK built */
    uint8_t ack_flags;               /* private: an ACK is due (0x80) and its flags */
    uint8_t len;                     /* encoded bytes of the frame being received (0xFF: skipping) */
    uint8_t tx_len;                  /* encoded ACK being sent: its length, */
    uint8_t tx_pos;                  /*   next byte */
    uint8_t buf[ATT_LINK2_WIRE_MAX]; /* frame being received (encoded) */
    uint8_t dec[ATT_LINK2_WIRE_MAX]; /* decoded frame */
    uint8_t tx[10];                  /* 0x00, encoded ACK (8), 0x00 */
} att_link2_receiver;

/* Attach `out` (ATT_LINK2_OUT_MAX bytes), zero the statistics, no session,
 * room 0 (set it with att_link2_receiver_set_room). ATT_OK or ATT_LINK2_E_NULL. */
int att_link2_receiver_init(att_link2_receiver *r, uint8_t *out);

/* Forget the session and any partial frame, statistics kept (a rebooted receiver). */
void att_link2_receiver_reset(att_link2_receiver *r);

/* The caller can take `room` more records (its free queue slots); the
 * receiver delivers at most that many and lowers it by each delivery.
 * When it widens a window that was narrower than one full frame, an ACK
 * (window update) is queued. */
void att_link2_receiver_set_room(att_link2_receiver *r, uint16_t room);

/* A byte arrived from A: ATT_LINK2_NONE, ATT_LINK2_DELIVERED (r->n_out
 * records, 6 bytes each, in the output buffer until the next sink: they are
 * acknowledged, the caller must keep them), ATT_LINK2_FRAME (valid, nothing
 * new: SYN, probe, duplicate, gap, or no room), ATT_LINK2_BAD_FRAME,
 * ATT_LINK2_DISCARDED, or an error. */
att_link2_result att_link2_receiver_sink(att_link2_receiver *r, uint8_t byte);

/* ATT_LINK2_SEND (*out_byte: the next byte of an ACK), ATT_LINK2_IDLE, or an
 * error. An ACK reports the state when its first byte is handed out. */
att_link2_result att_link2_receiver_poll(att_link2_receiver *r, uint8_t *out_byte);

/* ------------------------------------------------------------------ */
/* CRC (att_link2_crc_byte: link2_sender.c; att_link2_crc: _aux.c)   */
/* ------------------------------------------------------------------ */

/* CRC-32C register update with one byte (start from 0xFFFFFFFF; the CRC is
 * the register xor 0xFFFFFFFF). */
uint32_t att_link2_crc_byte(uint32_t reg, uint8_t byte);

/* CRC-32C of n bytes (check value of "123456789": 0xE3069283). */
uint32_t att_link2_crc(const uint8_t *data, uint16_t n);

ATT_API_END

#endif /* ATTITUDE_LINK2_H */
