/*
 * firmware/sim/fw_sim.h — simulation-only parts of the firmware image
 * (built with -DFW_SIM_MODEL): the TLC2543 + gyro device model behind the
 * driver's pins (tlc_hal_sim.h, tlc_model.c).
 */
#ifndef FW_SIM_H
#define FW_SIM_H

#include <stdint.h>

/* Reset the model (its state lives in unused SFR cells, not in RAM). */
void fw_sim_model_init(void);
/* Advance the analog inputs to the current time (before each scan). */
void fw_sim_model_step(void);
/* Report a protocol violation seen by the model and stop (EXIT 2). */
void fw_sim_model_check(void);
/* Gyro input evaluations so far (one per scan). */
uint16_t fw_sim_conversions(void);

#endif /* FW_SIM_H */
