"""Names of the timeline states and events the agents record (one place, so metrics,
figures and recordings agree)."""

# Activity track (mutually exclusive).
INIT = "init"  # assignment received -> starts moving
MOVING = "moving"  # navigating (includes re-planning and recovery)
DELAY = "delay"  # paused for a near collision, or queued at a one-lane passage
TASK = "task"  # at a task location, executing it (arrival -> status sent)
WAITING = "waiting"  # agenda not empty but nothing to do now (task not yet available)
IDLE = "idle"  # agenda complete, waiting for the team

# Events.
ASSIGNMENT_RECEIVED = "assignment_received"
STARTED_MOVING = "started_moving"
ARRIVED = "arrived"
TASK_COMPLETED = "task_completed"
NEAR_COLLISION = "near_collision"
NAV_ABORTED = "nav_aborted"
AGENDA_COMPLETE = "agenda_complete"
MADE_WAY = "made_way"  # stepped aside for a team mate
QUEUED = "queued"  # waited before a one-lane passage for a mate coming the other way
GOAL_OCCUPIED = "goal_occupied"  # arrived before its goal: a mate stood on it too long
OPERATOR_COMMAND = "operator_command"  # an operator's command reached the robot
TASK_DROPPED = "task_dropped"  # reached a task the operator had reassigned meanwhile

# Leader-Follower (activity track).
ROLE_ASSIGNMENT = "role_assignment"  # collecting utilities and roles
LEADER_DISCONNECT = "leader_disconnect"  # leader stopped, waiting for followers
FOLLOWER_WAITING = "follower_waiting"  # follower at the leader, waiting
SWITCHING = "switching"  # stopping / resuming between roles

# Role track (LF): na / leader / follower / assigning / regrouping.
ROLE_NA = "na"
ROLE_LEADER = "leader"
ROLE_FOLLOWER = "follower"
ROLE_ASSIGNING = "assigning"
ROLE_REGROUPING = "regrouping"

# LF events.
DISCONNECT_DETECTED = "disconnect_detected"
ROLE_ASSIGNED = "role_assigned"
ROLES_DISSOLVED = "roles_dissolved"
# rps: the rendezvous.
RENDEZVOUS = "rendezvous"  # activity: waiting at the meeting point
RENDEZVOUS_START = "rendezvous_start"  # event: leaves for the meeting point
RENDEZVOUS_END = "rendezvous_end"  # event: leaves the meeting point
STATUSES_RESHARED = "statuses_reshared"  # event: every known status published again

# lf-wait: a follower doing a task of its own near the group, and its leader waiting.
ROLE_DETOURING = "detouring"  # the role its poses carry meanwhile (a request to wait)
LEADER_DETOUR_WAIT = "leader_detour_wait"  # activity: leader waiting for such a follower
DETOUR = "detour"
DETOUR_ENDED = "detour_ended"
DIRECT_ROUTE = "direct_route"  # a follower's route would leave the connection area
