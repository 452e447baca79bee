# CHAI3D's device layer built from its sources (-DCHAI3D_SOURCE_DIR=/path/to/chai3d-3.3.0): the haptic device
# handler and the drivers it loads (Force Dimension through libdrd, Phantom through OpenHaptics loaded at run
# time, Leap, custom), with the system and timer classes they use. The rest of CHAI3D (graphics, audio, files,
# widgets) is left out: the bridge draws nothing. This takes about 15 s of one core where the whole library
# takes about 4 minutes of two, so CI builds and runs the bridge against the real CHAI3D device code.
#
# Defines the static library target `chai3d_devices` with its include directories, definitions and links.

if(NOT EXISTS "${CHAI3D_SOURCE_DIR}/src/devices/CHapticDeviceHandler.cpp")
  message(FATAL_ERROR "CHAI3D_SOURCE_DIR=${CHAI3D_SOURCE_DIR} is not a CHAI3D source tree "
                      "(no src/devices/CHapticDeviceHandler.cpp)")
endif()

file(GLOB chai3d_device_sources
  "${CHAI3D_SOURCE_DIR}/src/devices/*.cpp"
  "${CHAI3D_SOURCE_DIR}/src/system/*.cpp"
  "${CHAI3D_SOURCE_DIR}/src/timers/*.cpp")
# The X-Touch MIDI controller is not a haptic device and needs RtMidi and ALSA: not part of the handler.
list(FILTER chai3d_device_sources EXCLUDE REGEX "CXTouchController\\.cpp$")

add_library(chai3d_devices STATIC ${chai3d_device_sources})
target_include_directories(chai3d_devices SYSTEM PUBLIC
  "${CHAI3D_SOURCE_DIR}/src"
  "${CHAI3D_SOURCE_DIR}/externals/Eigen"
  "${CHAI3D_SOURCE_DIR}/externals/DHD/include")
target_compile_definitions(chai3d_devices PUBLIC ${CHAI3D_PLATFORM_DEFINITION})
if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
  # CHAI3D's own sources are not ours to warn about.
  target_compile_options(chai3d_devices PRIVATE -w)
endif()

if(CMAKE_SYSTEM_NAME MATCHES Linux)
  # Force Dimension's driver library (omega, delta, sigma, Novint Falcon) as CHAI3D ships it, and what it uses.
  set(chai3d_dhd "${CHAI3D_SOURCE_DIR}/externals/DHD/lib/lin-${CMAKE_SYSTEM_PROCESSOR}/libdrd.a")
  if(NOT EXISTS "${chai3d_dhd}")
    message(FATAL_ERROR "CHAI3D's Force Dimension library is missing: ${chai3d_dhd}")
  endif()
  find_library(chai3d_libusb NAMES usb-1.0)
  if(NOT chai3d_libusb)
    message(FATAL_ERROR "libusb-1.0 not found: Force Dimension's libdrd needs it (Debian: apt-get install libusb-1.0-0-dev)")
  endif()
  target_link_libraries(chai3d_devices PUBLIC "${chai3d_dhd}" "${chai3d_libusb}" Threads::Threads ${CMAKE_DL_LIBS} rt)
elseif(CMAKE_SYSTEM_NAME MATCHES Darwin)
  message(FATAL_ERROR "CHAI3D_SOURCE_DIR builds are written for Linux; on macOS build CHAI3D itself and set CHAI3D_DIR")
endif()
