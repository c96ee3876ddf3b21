/* The postback receive path as an integrator would write it from the vendor document
 * (gimbal-can-protocol-v1.1 section 2.2; CRC low byte first, see shared/spec/the protocol notes).
 * Deliberately plain: no gap bound, no counters, no checks beyond the header and the CRC. */
#include <string.h>
#include "postback_rx.h"

/* Note 3 of the document, pasted as it is. */
uint16_t wCRC_Table[] =
{
    0x0000, 0xCC01, 0xD801, 0x1400, 0xF001, 0x3C00, 0x2800, 0xE401,
    0xA001, 0x6C00, 0x7800, 0xB401, 0x5000, 0x9C01, 0x8801, 0x4400
};

uint16_t crc_fly16(u8 *pBuffer, uint16_t length) {
    uint16_t len = length;
    uint16_t tmp;
    uint16_t crcTmp;
    crcTmp = 0xFFFF;
    while (length-- > 0) {
        //crc_accumulate(*pBuffer++, &crcTmp);
        tmp = wCRC_Table[(pBuffer[len-length-1] ^ crcTmp) & 15] ^ (crcTmp >> 4);
        crcTmp = wCRC_Table[((pBuffer[len-length-1] >> 4) ^ tmp) & 15] ^ (tmp >> 4);
    }
    return (crcTmp);
}

struct gimbal_status gimbal_status;

static uint8_t rx_buf[32];
static uint8_t rx_frame = 4; /* frames received of the current message; 4 = waiting for EB 90 */

int on_frame(uint32_t id, const uint8_t data[8])
{
    uint16_t crc;

    if (id != POSTBACK_CAN_ID)
        return 0;

    if (data[0] == 0xEB && data[1] == 0x90)
        rx_frame = 0; /* a new message starts: drop whatever was collected */
    else if (rx_frame >= 4)
        return 0;     /* not inside a message */

    memcpy(&rx_buf[rx_frame * 8], data, 8);
    rx_frame++;
    if (rx_frame < 4)
        return 0;

    crc = crc_fly16(rx_buf, 25);
    if ((rx_buf[25] | (rx_buf[26] << 8)) != crc)
        return 0;

    gimbal_status.gimbal_type  = rx_buf[16];
    gimbal_status.tracking     = rx_buf[17];
    gimbal_status.control_mode = rx_buf[18];
    gimbal_status.pitch        = (int16_t)(rx_buf[19] | (rx_buf[20] << 8));
    gimbal_status.heading      = (uint16_t)(rx_buf[21] | (rx_buf[22] << 8));
    gimbal_status.motor_psi    = (int16_t)(rx_buf[23] | (rx_buf[24] << 8));
    return 1;
}

void encode_angle(uint8_t out[8], int type, int16_t value)
{
    out[0] = 0x0F;
    out[1] = 0x08;
    out[2] = (uint8_t)type;
    out[3] = (uint8_t)(value & 0xFF);
    out[4] = (uint8_t)((uint16_t)value >> 8);
    out[5] = 0;
    out[6] = 0;
    out[7] = 0;
}
