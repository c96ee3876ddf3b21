/* Postback receive path and angle command, written the straightforward way from the vendor
 * document (gimbal-can-protocol-v1.1, section 2.2). The C reference receive path. */
#ifndef POSTBACK_RX_H
#define POSTBACK_RX_H

#include <stdint.h>

#define POSTBACK_CAN_ID 0x030F0001u /* gimbal -> us, four 8-byte frames a message */
#define CONTROL_CAN_ID  0x00000F01u /* us -> gimbal */

typedef uint8_t u8;

struct gimbal_status {
    uint8_t  gimbal_type;  /* byte 16 */
    uint8_t  tracking;     /* byte 17 */
    uint8_t  control_mode; /* byte 18 */
    int16_t  pitch;        /* bytes 19-20, degrees x100 */
    uint16_t heading;      /* bytes 21-22, degrees x100 */
    int16_t  motor_psi;    /* bytes 23-24, degrees x100 */
};

/* The last good postback. */
extern struct gimbal_status gimbal_status;

/* Feed one received CAN frame (extended ID, 8 data bytes). Returns 1 when it completed a
 * postback message with a good CRC (gimbal_status then holds it), 0 otherwise. */
int on_frame(uint32_t id, const uint8_t data[8]);

/* "Specify angle" command: 0F 08 TT lo hi 00 00 00 (type 1 heading, 2 pitch, 3 zoom). */
void encode_angle(uint8_t out[8], int type, int16_t value);

/* The document's CRC (CRC-16/MODBUS, nibble table). */
uint16_t crc_fly16(u8 *pBuffer, uint16_t length);

#endif
