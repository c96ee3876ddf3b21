/* The C MAVLink library's side of qemu_bench_mavlink: the library pymavlink's mavgen
 * generates (C, MAVLink 2, common dialect), used as its own documentation and examples use
 * it, called from the Rust benchmark on the same bytes in the same QEMU run. */
#ifndef MAVLINK_C_H
#define MAVLINK_C_H

#include <stdint.h>

/* What the received bytes held, as the library decoded them. Mirrored by #[repr(C)]
 * struct CSeen in qemu_bench_mavlink.rs. */
typedef struct {
    uint32_t heartbeats;
    uint32_t setpoints;
    uint32_t states;
    uint32_t positions;
    uint32_t others;
    /* Frames the library dropped (bad CRC): packet_rx_drop_count. */
    uint32_t dropped;
    /* The last GIMBAL_DEVICE_SET_ATTITUDE. */
    float setpoint_q[4];
    uint16_t setpoint_flags;
    uint8_t setpoint_target_component;
    /* The last AUTOPILOT_STATE_FOR_GIMBAL_DEVICE. */
    float state_q[4];
    float state_angular_velocity_z;
    uint8_t state_landed_state;
    /* The last GLOBAL_POSITION_INT. */
    int32_t lat;
    int32_t lon;
    int32_t alt;
} c_seen_t;

/* GIMBAL_DEVICE_ATTITUDE_STATUS's fields. Mirrored by CStatus. */
typedef struct {
    uint32_t time_boot_ms;
    float q[4];
    float angular_velocity_x;
    float angular_velocity_y;
    float angular_velocity_z;
    uint32_t failure_flags;
    float delta_yaw;
    float delta_yaw_velocity;
    uint16_t flags;
    uint8_t target_system;
    uint8_t target_component;
    uint8_t gimbal_device_id;
} c_status_t;

/* Forgets what was received (the parser's state and c_seen). */
void c_reset(void);
/* Parses `len` bytes with mavlink_parse_char and decodes each message it completes with
 * its mavlink_msg_*_decode. */
void c_receive(const uint8_t *bytes, uint32_t len);
/* What c_receive saw. */
const c_seen_t *c_seen(void);
/* mavlink_msg_gimbal_device_attitude_status_pack + mavlink_msg_to_send_buffer, with
 * sequence number `seq`, into `out` (at least 280 bytes); its length. */
uint32_t c_send_status(uint8_t *out, uint8_t seq, uint8_t system, uint8_t component,
                       const c_status_t *s);
/* The same for HEARTBEAT (MAV_AUTOPILOT_INVALID, no mode, MAV_STATE_ACTIVE). */
uint32_t c_send_heartbeat(uint8_t *out, uint8_t seq, uint8_t system, uint8_t component,
                          uint8_t type);
/* The same for CAMERA_TRACKING_IMAGE_STATUS with no target position (NaN). */
uint32_t c_send_tracking_status(uint8_t *out, uint8_t seq, uint8_t system, uint8_t component,
                                uint8_t tracking_status, uint8_t tracking_mode);

#endif
