/*
 * firmware/sim/fw_sim.h — simulation-only parts of the firmware image
 * (built with -DFW_SIM): the TLC2543 + gyro device model behind the
 * driver's HAL, and output/stop through the uCsim simulator interface.
 */
#ifndef FW_SIM_H
#define FW_SIM_H

#include "attitude/tlc2543.h"

/* The (dummy) host-HAL pointer tlc2543_init() requires in a custom-HAL
 * build; the pin operations are the macros of tlc_hal_sim.h. */
const tlc2543_hal *fw_sim_adc_hal(void);

/* Reset the model (its state lives in unused SFR cells, not in RAM). */
void fw_sim_model_init(void);

/* Gyro conversions (AIN0..AIN2) the model has made so far. */
uint16_t fw_sim_conversions(void);

#endif /* FW_SIM_H */
