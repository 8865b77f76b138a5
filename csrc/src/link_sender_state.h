/*
 * libattitude — private: the sender's state values, shared by
 * link_sender.c and link_sender_aux.c (not a public header).
 */
#ifndef ATTITUDE_LINK_SENDER_STATE_H
#define ATTITUDE_LINK_SENDER_STATE_H

/* Private states. */
typedef enum {
    SS_IDLE = 0,      /* no block */
    SS_SEND_SYN,      /* next poll hands out 0xAA */
    SS_WAIT_SYN_ACK,  /* waiting for 0xBB (syn timer running) */
    SS_SEND_DATA,     /* next poll hands out block[index] */
    SS_SEND_CHECKSUM, /* next poll hands out the checksum */
    SS_WAIT_ANSWER,   /* waiting for 0x00 / 0xFF (answer timer running) */
    SS_TIMED_OUT,     /* a sink found the timer expired: next poll reports it */
    SS_GAVE_UP,       /* next poll reports the give-up */
    SS_COUNT
} ss_state;

#endif
