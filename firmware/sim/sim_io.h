/*
 * firmware/sim/sim_io.h — text output and stop through the uCsim simulator
 * interface on SFR 0xFF (s51 -I if=sfr[0xff],out=FILE): command 'w' writes
 * one character to the output file, 'r' reads one from the input file, 's'
 * stops the simulation. Hex numbers
 * only (no buffers: this costs no RAM but the call's return address).
 */
#ifndef FW_SIM_IO_H
#define FW_SIM_IO_H

#include <stdint.h>

void fw_sim_putc(char c);
void fw_sim_puts(const char *s);
void fw_sim_puthex(uint16_t v); /* four hex digits */
/* The next byte of the interface's input file (s51 -I ...,in=FILE; command
 * 'r'); 0 past its end. */
uint8_t fw_sim_getc(void);
/* Print "EXIT <code>" and stop the simulation; never returns. */
void fw_sim_stop(uint8_t code);

#endif /* FW_SIM_IO_H */
