# GENERATED from toolchain/app/optional.toml by `python -m toolchain.buildfiles`: do not edit.
# attitude-rx's optional dependencies: CMakeLists.txt probes each (header, symbol, libraries).
set(ATT_APP_OPTIONAL gpsd)
set(ATT_APP_OPTIONAL_gpsd_DEFINE ATT_RX_GPSD)
set(ATT_APP_OPTIONAL_gpsd_HEADER gps.h)
set(ATT_APP_OPTIONAL_gpsd_SYMBOL gps_open)
set(ATT_APP_OPTIONAL_gpsd_LIBS -lgps)
