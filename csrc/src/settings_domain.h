/*
 * libattitude — internal: the domain of each real field of a settings struct, as a table
 * walked in the struct's order, so a check names the first field out of its domain
 * (att_ahrs_check_settings_field, att_g9_check_settings_field). Not installed.
 */
#ifndef ATTITUDE_SETTINGS_DOMAIN_H
#define ATTITUDE_SETTINGS_DOMAIN_H

#include <stddef.h>

#include "att_math.h"

/* A field's value is finite and, by rule: */
enum {
    ATT__GT, /* above the bound */
    ATT__GE, /* at least the bound */
    ATT__ABS /* within ±bound */
};

typedef struct {
    const char *name;
    size_t offset;
    int rule;
    att_real bound;
} att__domain;

/* clang-format off */
#define ATT__DOMAIN(type, field, rule, bound) { #field, offsetof(type, field), rule, ATT_R(bound) }
/* clang-format on */

static inline int att__in_domain(const void *set, const att__domain *d)
{
    att_real v = *(const att_real *)(const void *)((const unsigned char *)set + d->offset);
    if (!isfinite(v)) {
        return 0;
    }
    return d->rule == ATT__GT ? v > d->bound : d->rule == ATT__GE ? v >= d->bound : att_fabs(v) <= d->bound;
}

/* The first entry of table[0..n) whose field of set is out of its domain, or NULL. */
static inline const att__domain *att__out_of_domain(const void *set, const att__domain *table, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++) {
        if (!att__in_domain(set, &table[i])) {
            return &table[i];
        }
    }
    return NULL;
}

#endif /* ATTITUDE_SETTINGS_DOMAIN_H */
