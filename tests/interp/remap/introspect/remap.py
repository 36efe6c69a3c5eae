from interpreter import INTERP_OK


def look(self, **words):
    block = self.blocks[self.remap_level]
    remap = block.executing_remap
    print(
        "--- %s of %s (argspec %s, ngc %s)"
        % (
            "prolog" if self.params["_phase"] == 0 else "epilog",
            remap.name,
            remap.argspec,
            remap.remap_ngc,
        )
    )
    print("words:", sorted(words.items()))
    print(
        "levels: call=%d remap=%d task=%d debugmask=%#x"
        % (self.call_level, self.remap_level, self.task, self.debugmask)
    )
    print(
        "block: p_flag=%s p=%.1f q_flag=%s x_flag=%s comment='%s' m_modes[10]=%d"
        % (
            block.p_flag,
            block.p_number,
            block.q_flag,
            block.x_flag,
            block.comment,
            block.m_modes[10],
        )
    )
    print("position: %.3f %.3f %.3f" % (self.current_x, self.current_y, self.current_z))
    print(
        "feed=%.1f speed=%.1f motion_mode=%d plane=%d units=%d"
        % (self.feed_rate, self.speed[0], self.motion_mode, self.plane, self.length_units)
    )
    print(
        "tools: current=%d selected=%d current_pocket=%d selected_pocket=%d"
        % (self.current_tool, self.selected_tool, self.current_pocket, self.selected_pocket)
    )
    print(
        "tool 0: %d z=%.4f d=%.4f; tool_offset z=%.4f"
        % (
            self.tool_table[0].toolno,
            self.tool_table[0].offset.z,
            self.tool_table[0].diameter,
            self.tool_offset.z,
        )
    )
    print(
        "cutter_comp_side=%d return_value=%.1f value_returned=%d toolchange_flag=%s"
        % (self.cutter_comp_side, self.return_value, self.value_returned, self.toolchange_flag)
    )
    print(
        "params: #5220=%.1f _ini[setup]value=%.1f _feed=%.1f locals=%s"
        % (
            self.params[5220],
            self.params["_ini[setup]value"],
            self.params["_feed"],
            self.params.locals(),
        )
    )
    print("g codes:", list(self.active_g_codes)[1:])
    print("m codes:", list(self.active_m_codes)[1:])
    self.params["_phase"] = 1
    return INTERP_OK
