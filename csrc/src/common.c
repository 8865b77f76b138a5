/* libattitude — common helpers. */
#include "attitude/common.h"
#include "attitude/integrator.h"

const char *att_status_str(int status)
{
    switch (status) {
    case ATT_OK:
        return "ok";
    case ATT_E_NULL:
        return "NULL pointer argument";
    case ATT_E_ARG:
        return "argument out of range";
    case ATT_E_NONFINITE:
        return "non-finite input (NaN or Inf)";
    case ATT_E_RANGE:
        return "value outside representable range";
    case ATT_E_STATE:
        return "call not valid in current state";
    case ATT_E_TIMEOUT:
        return "timeout";
    case ATT_E_BUFFER:
        return "buffer too small";
    case ATT_E_INTEG_METHOD:
        return "unknown integration method, or a call not valid for it";
    case ATT_E_INTEG_DIVERGED:
        return "finite input but a non-finite result";
    case ATT_E_INTEG_RANGE:
        return "increment beyond pi rad per sample";
    default:
        return "unknown status";
    }
}

int att_real_size(void)
{
    return (int)sizeof(att_real);
}
