#include "snake_autonomy/dynamixel/conversions.hpp"

#include "snake_autonomy/dynamixel/protocol.hpp"

namespace snake_autonomy::dynamixel {

ServoFeedback decode_feedback(const std::uint8_t* block, const UnitScales& s) noexcept {
  ServoFeedback f;
  f.current_a = current_to_amps(static_cast<std::int16_t>(get_le(block, 2, true)), s);
  f.velocity_rad_s = velocity_to_rad_s(get_le(block + 2, 4, true), s);
  f.position_ticks = get_le(block + 6, 4, true);
  f.position_rad = ticks_to_rad(f.position_ticks, s);
  return f;
}

}  // namespace snake_autonomy::dynamixel
