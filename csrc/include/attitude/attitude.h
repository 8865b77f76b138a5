/*
 * libattitude umbrella header: include this to get the whole public API.
 * Each module adds exactly one line here.
 */
#ifndef ATTITUDE_ATTITUDE_H
#define ATTITUDE_ATTITUDE_H

#include "attitude/common.h"
#include "attitude/version.h"
#include "attitude/tlc2543.h"
#include "attitude/quat.h"
#include "attitude/integrator.h"
#include "attitude/link.h"
#include "attitude/link2.h"
#include "attitude/block.h"
#include "attitude/sensor.h"
#include "attitude/fixed.h"
#include "attitude/ad7927.h"
#include "attitude/denoise.h"
#include "attitude/aiding.h"
#include "attitude/ahrs.h"
#include "attitude/ahrs_thesis.h"
#include "attitude/ahrs_gnss9.h"
#include "attitude/gnss.h"

#endif /* ATTITUDE_ATTITUDE_H */
