/* See mavlink_c.h. Built by benches/mcu/build.rs with arm-none-eabi-gcc -O2 for the
 * Cortex-M4F, against the headers scripts/bench.sh generates with pymavlink's mavgen. */
#define MAVLINK_NO_CONVERSION_HELPERS
#include <common/mavlink.h>
#include <math.h>

#include "mavlink_c.h"

#define CHAN MAVLINK_COMM_0

static c_seen_t seen;

void c_reset(void) {
    mavlink_reset_channel_status(CHAN);
    mavlink_get_channel_status(CHAN)->packet_rx_drop_count = 0;
    seen = (c_seen_t){0};
}

const c_seen_t *c_seen(void) {
    seen.dropped = mavlink_get_channel_status(CHAN)->packet_rx_drop_count;
    return &seen;
}

void c_receive(const uint8_t *bytes, uint32_t len) {
    mavlink_message_t msg;
    mavlink_status_t status;
    for (uint32_t i = 0; i < len; i++) {
        if (!mavlink_parse_char(CHAN, bytes[i], &msg, &status)) {
            continue;
        }
        switch (msg.msgid) {
        case MAVLINK_MSG_ID_HEARTBEAT: {
            mavlink_heartbeat_t hb;
            mavlink_msg_heartbeat_decode(&msg, &hb);
            seen.heartbeats++;
            break;
        }
        case MAVLINK_MSG_ID_GIMBAL_DEVICE_SET_ATTITUDE: {
            mavlink_gimbal_device_set_attitude_t s;
            mavlink_msg_gimbal_device_set_attitude_decode(&msg, &s);
            seen.setpoints++;
            memcpy(seen.setpoint_q, s.q, sizeof s.q);
            seen.setpoint_flags = s.flags;
            seen.setpoint_target_component = s.target_component;
            break;
        }
        case MAVLINK_MSG_ID_AUTOPILOT_STATE_FOR_GIMBAL_DEVICE: {
            mavlink_autopilot_state_for_gimbal_device_t s;
            mavlink_msg_autopilot_state_for_gimbal_device_decode(&msg, &s);
            seen.states++;
            memcpy(seen.state_q, s.q, sizeof s.q);
            seen.state_angular_velocity_z = s.angular_velocity_z;
            seen.state_landed_state = s.landed_state;
            break;
        }
        case MAVLINK_MSG_ID_GLOBAL_POSITION_INT: {
            mavlink_global_position_int_t p;
            mavlink_msg_global_position_int_decode(&msg, &p);
            seen.positions++;
            seen.lat = p.lat;
            seen.lon = p.lon;
            seen.alt = p.alt;
            break;
        }
        default:
            seen.others++;
            break;
        }
    }
}

uint32_t c_send_status(uint8_t *out, uint8_t seq, uint8_t system, uint8_t component,
                       const c_status_t *s) {
    mavlink_message_t msg;
    mavlink_get_channel_status(CHAN)->current_tx_seq = seq;
    mavlink_msg_gimbal_device_attitude_status_pack_chan(
        system, component, CHAN, &msg, s->target_system, s->target_component,
        s->time_boot_ms, s->flags, s->q, s->angular_velocity_x, s->angular_velocity_y,
        s->angular_velocity_z, s->failure_flags, s->delta_yaw, s->delta_yaw_velocity,
        s->gimbal_device_id);
    return mavlink_msg_to_send_buffer(out, &msg);
}

uint32_t c_send_heartbeat(uint8_t *out, uint8_t seq, uint8_t system, uint8_t component,
                          uint8_t type) {
    mavlink_message_t msg;
    mavlink_get_channel_status(CHAN)->current_tx_seq = seq;
    mavlink_msg_heartbeat_pack_chan(system, component, CHAN, &msg, type,
                                    MAV_AUTOPILOT_INVALID, 0, 0, MAV_STATE_ACTIVE);
    return mavlink_msg_to_send_buffer(out, &msg);
}

uint32_t c_send_tracking_status(uint8_t *out, uint8_t seq, uint8_t system, uint8_t component,
                                uint8_t tracking_status, uint8_t tracking_mode) {
    mavlink_message_t msg;
    mavlink_get_channel_status(CHAN)->current_tx_seq = seq;
    mavlink_msg_camera_tracking_image_status_pack_chan(
        system, component, CHAN, &msg, tracking_status, tracking_mode, 0, NAN, NAN, NAN,
        NAN, NAN, NAN, NAN, 0);
    return mavlink_msg_to_send_buffer(out, &msg);
}
