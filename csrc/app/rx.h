/*
 * attitude-rx — receiver app of the Linux computer (paper sec. 3.3–3.4,
 * Fig. 6): link receiver thread + attitude thread joined by a bounded
 * sample queue. Private header of csrc/app (not part of libattitude).
 */
#ifndef ATTITUDE_RX_H
#define ATTITUDE_RX_H

#include <stddef.h>
#include <stdint.h>
#include <pthread.h>
#include <time.h>

#include "attitude/attitude.h"

/* Exit codes (the BSD sysexits values, so shell scripts can tell them apart). */
enum {
    RX_EXIT_OK = 0,
    RX_EXIT_USAGE = 64,       /* bad command line */
    RX_EXIT_UNAVAILABLE = 69, /* --gnss gpsd: gpsd unreachable, or gpsd support not built in */
    RX_EXIT_NOPORT = 66,      /* port does not exist */
    RX_EXIT_INTERNAL = 70,
    RX_EXIT_IOERR = 74,    /* port cannot be configured (not a tty...), or stdout failed */
    RX_EXIT_TEMPFAIL = 75, /* stopped while stdout stayed blocked: acknowledged samples unprinted */
    RX_EXIT_NOPERM = 77,   /* no permission to open the port */
    RX_EXIT_CONFIG = 78    /* bad config file or value */
};

enum {
    RX_QUEUE_MAX = 4096,    /* largest --queue */
    RX_REPORT_RESERVE = 64, /* queue slots beyond --queue that only reports may take */
    RX_RECORDS_MAX = ATT_LINK_BLOCK_MAX / ATT_BLOCK_SIZE, /* records in one link block */
    RX_PATH_MAX = 256,
    RX_MSG_MAX = 256,
    RX_LINE_MAX = 2048,      /* one output or log line (a filter line with its GNSS fix: ~1200) */
    RX_HOLD_MS_DEFAULT = 20, /* --hold-ms: below the senders' 50 ms answer timeout (docs/attitude-rx.md) */
    RX_HOLD_MS_MAX = 10000,
    RX_STOP_GRACE_MS = 500 /* after a stop request, time left to print what was acknowledged */
};

#define RX_VERSION "0.1.0" /* the project's version (pyproject.toml; a test keeps them equal) */

/* Default sample period until a BOOT report says otherwise: the firmware's
 * default, 72 ticks of 1/3600 s (docs/firmware.md). */
#define RX_PERIOD_DEFAULT (72.0 / 3600.0)

/* Nominal conversions of the aided board's accelerometer and magnetometer (the
 * defaults of acc-* and mag-*; `attitude calibrate` writes measured ones). */
#define RX_ACC_ZERO  2048.0            /* ratiometric: 0 g at half the supply */
#define RX_ACC_SCALE (9.80665 / 409.6) /* m/s² per code: 0.1 of the supply per g (ADXL335 class) */
#define RX_MAG_ZERO  2047.5            /* set/reset code (c_set + 4095 - c_reset) / 2 at zero field */
#define RX_MAG_SCALE (100.0 / 819.2)   /* µT per code: 1 mV/V/gauss bridge x gain 200 (HMC1043 + AD623) */

/* What the command line asks for. */
typedef enum {
    RX_RUN = 0,
    RX_HELP = 1,
    RX_VERSION_INFO = 2
} rx_action;

typedef enum {
    RX_FORMAT_CSV = 0,
    RX_FORMAT_JSONL = 1
} rx_format;

/* The estimator (--estimator): auto chooses per stream from its CHANNELS report. */
typedef enum {
    RX_EST_AUTO = 0,      /* ahrs when the stream announces accelerometer and magnetometer */
    RX_EST_AHRS = 1,      /* att_ahrs: gyro bias, accelerometer and magnetometer aiding */
    RX_EST_INTEGRATOR = 2 /* att_integ: the gyros alone, open loop (the paper's) */
} rx_estimator;

/* One three-axis sensor's conversion (attitude/sensor.h): the gyro-*, acc-*, mag-* keys. */
typedef struct {
    double zero[3];  /* ADC code at zero input, per channel */
    double scale[3]; /* units per code, per channel: rad/s (gyro), m/s² (acc), µT (mag) */
    int axis_src[3]; /* body axis i = sign[i] * channel axis_src[i] */
    int axis_sign[3];
    double mat[9];  /* correction M, row-major (identity) */
    double bias[3]; /* correction b, output units (0) */
} rx_sensor_cfg;

/* The GNSS input (--gnss): none, a serial port read with the library's parser, or gpsd. */
typedef enum {
    RX_GNSS_OFF = 0,
    RX_GNSS_SERIAL = 1, /* --gnss /dev/ttyS1[:BAUD] */
    RX_GNSS_GPSD = 2    /* --gnss gpsd[:HOST[:PORT]] */
} rx_gnss_kind;

enum {
    RX_GNSS_BAUD_DEFAULT = 9600, /* u-blox and most NMEA receivers' factory rate */
    RX_GNSS_HOST_MAX = 128,
    RX_GNSS_SERVICE_MAX = 16
};
#define RX_GPSD_HOST_DEFAULT "localhost"
#define RX_GPSD_PORT_DEFAULT "2947" /* gpsd's IANA port */

typedef struct {
    rx_gnss_kind kind;
    char path[RX_PATH_MAX];            /* serial: the device */
    long baud;                         /* serial: bits per second */
    char host[RX_GNSS_HOST_MAX];       /* gpsd: host name or address */
    char service[RX_GNSS_SERVICE_MAX]; /* gpsd: TCP port */
} rx_gnss_spec;

/* Parse a --gnss argument ("/dev/ttyS1", "/dev/ttyS1:115200", "gpsd",
 * "gpsd:HOST", "gpsd:HOST:PORT"; "off"): 0, or RX_EXIT_CONFIG with a message. */
int rx_gnss_parse(const char *arg, rx_gnss_spec *out, char *msg, size_t msglen);

/* Everything the command line / config file sets. */
typedef struct {
    char port[RX_PATH_MAX];
    long baud;      /* bits per second */
    double period;  /* s, gyro sample period (until a BOOT report announces it) */
    int period_set; /* --period given (command line or config file): BOOT does not override it */
    rx_sensor_cfg gyro, acc, mag;
    att_method method;
    int method_set;         /* --method given: the filter's too (else its default, rv3-reuse) */
    rx_estimator estimator; /* --estimator */
    att_ahrs_settings ahrs; /* the filter's settings (keys: the field names); .method from method */
    rx_format format;
    unsigned block_size;   /* link block N: a multiple of 6 (3 x 16-bit codes per sample) */
    unsigned queue_size;   /* samples the queue holds (1..RX_QUEUE_MAX) */
    unsigned gap_ms;       /* link receiver gap timeout, ms */
    unsigned hold_ms;      /* how long an answer waits for room in a full queue, ms */
    unsigned long count;   /* stop after this many output lines (0 = run until signalled) */
    double consumer_delay; /* s the attitude thread sleeps per sample (diagnostics/tests) */
    double reopen_delay;   /* s between attempts to reopen a port that went away */
    int header;            /* print the CSV header line */
    int link;              /* RX_LINK_AUTO (default), RX_LINK_V2, RX_LINK_LEGACY */
    rx_gnss_spec gnss;     /* --gnss (default off) */
    double gnss_latency;   /* s, a fix's time of validity to the arrival of its last byte at
                              attitude-rx (gpsd: of its report); default 0, domain 0..2 */
} rx_config;

/* Link protocols (--link): the paper's handshake, link v2 (attitude/link2.h), or
 * whichever is heard first (legacy: an accepted block whose records decode;
 * v2: a valid frame), the default. */
enum {
    RX_LINK_LEGACY = 0,
    RX_LINK_V2 = 1,
    RX_LINK_AUTO = 2
};

/* Defaults: 9600 baud, period 0.02 s (RX_PERIOD_DEFAULT), zero 2048,
 * scale = 90 deg/s per 2048 codes, axes x,y,z, rv3, CSV, N = 6, queue 256,
 * gap 20 ms, hold 20 ms, link auto, estimator auto, the filter's defaults
 * (att_ahrs_default_settings), the accelerometer's and magnetometer's
 * nominal conversions (RX_ACC_*, RX_MAG_*), no corrections. */
void rx_config_defaults(rx_config *c);

/* Parse argv with getopt_long (and the --config files it names, whose
 * values the command line overrides). Returns 0, or an RX_EXIT_* code with
 * a message in msg (an unknown option names itself). Sets *action to
 * RX_HELP for -h/--help, RX_VERSION_INFO for --version (whichever comes
 * first; the rest of the line is then not checked). */
int rx_config_parse(rx_config *c, int argc, char **argv, rx_action *action, char *msg, size_t msglen);

/* Apply one "name value" setting (long option name without "--"). */
int rx_config_set(rx_config *c, const char *name, const char *value, char *msg, size_t msglen);

/* Read a config file of "name = value" lines ('#' comments). */
int rx_config_file(rx_config *c, const char *path, char *msg, size_t msglen);

const char *rx_method_name(att_method m);

/* Does a sample every `period` s, sent in link blocks of `block_size`
 * bytes (block_size / 6 samples each), fit a line of `baud` bits/s? One
 * exchange of the handshake protocol is block_size + 4 bytes of 10 bits
 * (8N1), one after the other (each side waits for the other's byte), so
 * the line carries at most baud / (10 (block_size + 4)) blocks/s. Returns
 * 0 if the rate fits, 1 with the numbers in msg if it does not. */
int rx_rate_check(long baud, unsigned block_size, double period, char *msg, size_t msglen);

/* A converter (attitude/sensor.h) of one sensor's zero, scale, axes and
 * correction: att_sensor_init's or att_sensor_set_correction's status. */
int rx_sensor_init(const rx_sensor_cfg *c, att_sensor *s);

/* The filter settings a config file or the command line may set, by their
 * att_ahrs_settings field names (every att_real field; method is the
 * shared --method): name i (0, 1, ... until NULL) and its value in *set. */
const char *rx_ahrs_setting(size_t i, const att_ahrs_settings *set, double *value);

/* The estimator a stream runs: --estimator, or with auto the stream's
 * channel set (ATT_BLOCK_CH_* bits; gyro only before a CHANNELS report). */
rx_estimator rx_estimator_for(rx_estimator chosen, unsigned channels);

const char *rx_estimator_name(rx_estimator e);

void rx_usage(const char *prog, void *stream);

/* ---- bounded record queue (one producer, one consumer) ---- */
/* One record of an accepted block, decoded and numbered by the receiver
 * thread (attitude/block.h), in stream order. */
typedef struct {
    att_block blk;       /* the record (a sample: blk.kind == ATT_BLOCK_SAMPLE) */
    att_block_span span; /* its place in the numbering (sample: span.first = its number) */
    int status;          /* att_block_decode's status (ATT_BLOCK_E_CODE: bad sample) */
    int seq_status;      /* att_block_seq_feed's status (ATT_BLOCK_E_SEQ: numbering slipped) */
    int closes;          /* a sample record that completes its sample's group (the tracker's
                            next record is a gyro record): every gyro-only sample closes */
    double wall;         /* s, CLOCK_MONOTONIC when the receiver thread took it (GNSS alignment) */
    uint8_t raw[ATT_BLOCK_SIZE];
} rx_item;

typedef struct {
    pthread_mutex_t lock;
    pthread_cond_t nonempty, notfull; /* notfull: CLOCK_MONOTONIC timed waits */
    rx_item buf[RX_QUEUE_MAX + RX_REPORT_RESERVE];
    unsigned cap, head, count;
    unsigned long pushed, popped;
    unsigned high_water;
    unsigned long failed; /* sample periods the integrator rejected (the attitude thread tells) */
    int closed;
} rx_queue;

int rx_queue_init(rx_queue *q, unsigned cap);
void rx_queue_destroy(rx_queue *q);
/* Queue all n records of one block, or none: wait until there is room for
 * all of them (samples fill up to cap items; reports may use
 * RX_REPORT_RESERVE more, so a BOOT or a loss report does not wait behind
 * a backlog of samples) or until `deadline` (CLOCK_MONOTONIC). 0 = queued,
 * 1 = still full at the deadline (nothing queued). Never drops. */
int rx_queue_push_all(rx_queue *q, const rx_item *items, unsigned n, const struct timespec *deadline);
/* Blocking until an item or the queue is closed and empty: 0 = got one, 1 = closed. */
int rx_queue_pop(rx_queue *q, rx_item *it);
void rx_queue_close(rx_queue *q);
/* The attitude thread could not integrate one sample period. */
void rx_queue_count_failed(rx_queue *q);
unsigned long rx_queue_failed(rx_queue *q);
/* Records that fit now whatever their kind (cap - count): the room link v2 advertises. */
unsigned rx_queue_room(rx_queue *q);

/* ---- stop requests and bounded I/O ---- */
/* A self-pipe that a signal handler or a thread writes one byte into to
 * request the stop; it is never read, so it stays readable and every
 * thread can poll it. The first thread to see it starts the grace time:
 * RX_STOP_GRACE_MS to print what is queued, then output is abandoned. */
typedef struct {
    int wake_rd, wake_wr;
    pthread_mutex_t lock;
    int stopping;             /* the request was seen */
    struct timespec deadline; /* CLOCK_MONOTONIC: end of the grace time */
} rx_stop;

int rx_stop_init(rx_stop *s);
/* Request the stop (async-signal-safe). */
void rx_stop_request(rx_stop *s);
/* Has a stop been requested? (polls the pipe without waiting) */
int rx_stop_check(rx_stop *s);
/* Wait up to `seconds` for a stop request: 1 if one came. */
int rx_stop_wait(rx_stop *s, double seconds);
/* Give the private copy of `fd` (stdout, stderr) its own non-blocking
 * open file description when it is a pipe or a character device (a tty),
 * by reopening /proc/self/fd/N: the shell's description stays blocking.
 * Otherwise (regular file, socket, no /proc) the fd is kept as it is and
 * rx_out_write polls before writing at most PIPE_BUF bytes. */
void rx_out_private(int fd);
/* Write n bytes to fd (stdout, stderr), waiting in poll() for room or a
 * stop request; once the stop is requested, only until its grace time
 * ends. 0 = written, 1 = abandoned (stopping and the fd stayed blocked),
 * -1 = write error (errno: EPIPE for a closed pipe, ...). */
int rx_out_write(rx_stop *s, int fd, const char *p, size_t n);
/* One line of log on stderr ("attitude-rx: " + fmt), through rx_out_write. */
void rx_log(rx_stop *s, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* Write n bytes to the (non-blocking) serial port, waiting in poll() for
 * room: 0 = written, 1 = a stop was requested first (not all written),
 * -1 = error (errno). */
int rx_port_write(rx_stop *s, int fd, const uint8_t *p, size_t n);

/* ---- serial port ---- */
/* Open and configure `path` raw 8N1 at `baud`, non-blocking (reads and
 * writes wait in poll()). Returns the fd, or -1 with errno set and a
 * message in msg. */
int rx_serial_open(const char *path, long baud, char *msg, size_t msglen);
/* The exit code of a port that rx_serial_open could not open (errno err): 66, 77 or 74. */
int rx_open_error_code(int err);
/* 1 if baud is one the termios layer knows: these. */
#define RX_BAUDS_TEXT "1200 2400 4800 9600 19200 38400 57600 115200 230400"
int rx_serial_baud_ok(long baud);
/* Close the port once what was written has gone out: the last answer
 * (the 0x00 of a block the app delivered, a link v2 ACK) reaches the
 * sender. Discarding it (TCOFLUSH; on a pty that empties what the other
 * end has not taken in yet) made a slow sender resend a block the app had
 * acknowledged. The port has no flow control, so its output drains at the
 * line's rate; output that does not move for RX_DRAIN_STUCK_MS (flow
 * stopped: tcflow TCOOFF) is dropped, as a tty's close() would wait for it
 * up to 30 s. */
enum {
    RX_DRAIN_STUCK_MS = 100
};
void rx_serial_close(int fd);

/* ---- GNSS input (rx_gnss.c; gpsd: rx_gpsd.c) ---- */
enum {
    RX_GNSS_QUEUE = 64,   /* fixes waiting for the attitude thread (the oldest dropped beyond) */
    RX_GNSS_QUIET_MS = 50 /* serial: a silence this long ends the NMEA epoch being merged */
};
#define RX_GNSS_LATENCY_MAX 2.0 /* s, largest gnss_latency */

/* One fix as the input thread read it: CLOCK_MONOTONIC time of its last byte (gpsd: its report). */
typedef struct {
    att_gnss_fix fix;
    double wall; /* s */
} rx_gnss_item;

/* Counters of the input (the end-of-run "gnss:" line). */
typedef struct {
    unsigned long fixes;   /* fixes read (parser, or gpsd reports with a mode) */
    unsigned long dropped; /* fixes the attitude thread never took (queue full: no board stream) */
    unsigned long reports; /* gpsd: reports read (TPV, SKY, ...) */
    unsigned long lost;    /* the port or the gpsd connection went away */
    att_gnss_stats parser; /* serial: the parser's counters */
} rx_gnss_counts;

typedef struct {
    rx_gnss_spec spec;
    rx_stop *stop;
    double reopen_delay; /* s between attempts to reopen a lost port or connection */
    int fd;              /* the serial port or gpsd's socket; -1 while lost */
    void *gpsd;          /* struct gps_data_t (rx_gpsd.c) */
    att_gnss_parser parser;
    pthread_t thread;
    int started;
    pthread_mutex_t lock; /* guards what follows */
    rx_gnss_item q[RX_GNSS_QUEUE];
    unsigned head, count;
    rx_gnss_counts n;
} rx_gnss;

/* Open the input of spec (nothing for RX_GNSS_OFF): 0, or an RX_EXIT_* code with a
 * message (port: 66 / 74 / 77 as the board's; gpsd: RX_EXIT_UNAVAILABLE). */
int rx_gnss_open(rx_gnss *g, const rx_gnss_spec *spec, rx_stop *stop, double reopen_delay, char *msg,
                 size_t msglen);
/* Start the input thread (0, or -1); it ends at the stop request, after taking what was
 * already readable. */
int rx_gnss_start(rx_gnss *g);
void rx_gnss_end(rx_gnss *g); /* join the thread, close */
/* The oldest fix waiting (1), or none (0); rx_gnss_pop removes it. */
int rx_gnss_peek(rx_gnss *g, rx_gnss_item *out);
void rx_gnss_pop(rx_gnss *g);
/* Queue a fix read at `wall` (the input threads). */
void rx_gnss_push(rx_gnss *g, const att_gnss_fix *fix, double wall);
rx_gnss_counts rx_gnss_counters(rx_gnss *g);
double rx_mono_now(void); /* CLOCK_MONOTONIC, s */

/* The board stream's clock seen from CLOCK_MONOTONIC (the attitude thread's): each
 * sample read at wall time w ends at stream time t (the sum of the sample periods),
 * so w - t is the sample's transport delay plus a constant; the smallest is the
 * least delayed sample's, and wall - offset is the stream time of a wall time.
 * The minimum leaks upward by RX_GNSS_CLOCK_LEAK s per s of stream, so a board
 * crystal slower than the host's (up to 10 times the 100 ppm of a cheap one) is
 * followed, never the delays of a backlog. */
#define RX_GNSS_CLOCK_LEAK 1e-3
typedef struct {
    double offset; /* s, wall - stream time */
    double t;      /* s, stream time of the last sample seen */
    int known;     /* a sample was seen */
} rx_gnss_clock;

/* A sample read at `wall` ends at stream time t. */
void rx_gnss_clock_sample(rx_gnss_clock *c, double wall, double t);
/* The stream time of a fix read at `wall` that was valid `latency` s before (needs c->known). */
double rx_gnss_clock_time(const rx_gnss_clock *c, double wall, double latency);
/* ,"gnss":{...} of docs/gnss.md for fix f, age_s old at the line, from `source`. */
int rx_gnss_json(char *p, size_t len, const att_gnss_fix *f, double age_s, const char *source);
/* The source's name in JSON and logs: "serial" or "gpsd". */
const char *rx_gnss_source(rx_gnss_kind k);

/* gpsd (rx_gpsd.c): built with libgps when ATT_RX_GPSD is defined, else these say so. */
extern const int rx_gpsd_built;
/* Connect and start watching: 0, or RX_EXIT_UNAVAILABLE with a message. */
int rx_gpsd_open(rx_gnss *g, char *msg, size_t msglen);
/* Read the reports waiting on g->fd, queueing each fix (wall: now): 0, or -1 lost. */
int rx_gpsd_read(rx_gnss *g);
void rx_gpsd_close(rx_gnss *g);

#endif /* ATTITUDE_RX_H */
