/*
 * libattitude — private: the link v2 sender's state values, shared by
 * link2_sender.c and link2_sender_aux.c (not a public header).
 */
#ifndef ATTITUDE_LINK2_PRIVATE_H
#define ATTITUDE_LINK2_PRIVATE_H

/* Session (att_link2_sender.session). */
typedef enum {
    SES_SYN_SEND = 0, /* the next frame is a SYN at base */
    SES_SYN_WAIT,     /* SYN sent, waiting for its SYNACK (timer running) */
    SES_RUN,          /* streaming */
    SES_BAD           /* init failed: every call reports an error */
} l2_session;

/* Emitter (att_link2_sender.tx): what the next poll hands out. */
typedef enum {
    TX_IDLE = 0, /* between frames: poll decides what to send */
    TX_LEAD,     /* the 0x00 before a frame after an idle line */
    TX_BODY,     /* encoded frame bytes, then the final code */
    TX_DELIM     /* the 0x00 that ends the frame */
} l2_tx;

/* Flags (att_link2_sender.flags). */
enum {
    FL_LINE_IDLE = 0x01, /* the last poll had nothing to send: lead the next frame with 0x00 */
    FL_EPOCH = 0x20      /* the epoch bit (= ATT_LINK2_E_BIT), toggled at each go-back */
};

#endif
