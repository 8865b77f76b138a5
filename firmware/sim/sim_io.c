/* firmware/sim/sim_io.c — see sim_io.h. */
#include "sim_io.h"

__sfr __at(0xff) FW_SIM_SIF;

void fw_sim_putc(char c)
{
    FW_SIM_SIF = 'w';
    FW_SIM_SIF = (unsigned char)c;
}

uint8_t fw_sim_getc(void)
{
    FW_SIM_SIF = 'r';
    return FW_SIM_SIF;
}

void fw_sim_puts(const char *s)
{
    while (*s) {
        fw_sim_putc(*s++);
    }
}

void fw_sim_puthex(uint16_t v)
{
    uint8_t i;
    for (i = 0; i < 4u; i++) {
        uint8_t d = (uint8_t)(v >> 12);
        fw_sim_putc((char)(d < 10u ? '0' + d : 'A' - 10 + d));
        v <<= 4;
    }
}

void fw_sim_stop(uint8_t code)
{
    fw_sim_puts("EXIT ");
    fw_sim_putc((char)('0' + code));
    fw_sim_putc('\n');
    FW_SIM_SIF = 's';
    for (;;) {
    }
}
