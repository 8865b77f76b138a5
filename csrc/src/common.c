/* libattitude — common helpers. */
#include "attitude/common.h"

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
    default:
        return "unknown status";
    }
}

int att_real_size(void)
{
    return (int)sizeof(att_real);
}
